"""Scripted teachers of the robot tasks: they play in place of the person of 5.4 (see docs/RECONSTRUCTION.md)."""

from __future__ import annotations

import heapq
import math

import numpy as np

from connrl.envs.robot.constants import (
    MOVE_BACKWARD,
    MOVE_FORWARD,
    ROBOT_RADIUS,
    TURN_LEFT_15,
    TURN_LEFT_60,
    TURN_RIGHT_15,
    TURN_RIGHT_60,
)
from connrl.envs.robot.sim import RobotSim, wrap_deg


# ---------------------------------------------------------------------------------------------------
# Scripted teachers (5.4: "I placed the robot at a manually-chosen start position and did my best")
def _steer(pose, target, tol: float = 7.5) -> int:
    """Turn towards ``target`` (60 deg turns for big errors, 15 for small), else move forward."""
    x, y, h = pose
    err = wrap_deg(math.degrees(math.atan2(target[1] - y, target[0] - x)) - h)
    return _turn_towards(err, tol)


def _turn_towards(err: float, tol: float = 7.5) -> int:
    if abs(err) > 37.5:
        return TURN_LEFT_60 if err > 0 else TURN_RIGHT_60
    if abs(err) > tol:
        return TURN_LEFT_15 if err > 0 else TURN_RIGHT_15
    return MOVE_FORWARD


def _run(env, start, policy, seed) -> list[tuple]:
    obs, info = env.reset(seed=seed, options={"start": start})
    lesson = []
    for _ in range(env.unwrapped.max_steps):
        a = policy(env.unwrapped)
        nobs, r, term, trunc, info = env.step(a)
        lesson.append((obs, a, r, nobs, term, trunc))
        obs = nobs
        if term or trunc:
            break
    return lesson


def teach_dp(env, start, seed: int | None = None) -> list[tuple]:
    """Demonstrate door passing from ``start`` through the nearest door.

    Go to a point 40 in in front of the door, then drive through while keeping the centre within 3 in
    of the door's axis (a one-step look-ahead on the lateral offset; the body clears the door jambs
    for offsets under half the door width minus the 12-in radius: 12.5 in for the 49-in doors). Returns the
    lesson as (obs, action, reward, next_obs, terminated, truncated) tuples.
    """
    u = env.unwrapped
    x, y, _ = start
    door = min(u.layout.doors.values(), key=lambda d: math.hypot(*(d.center - (x, y))))
    x0, y0, x1, y1 = door.segment
    along = np.array([x1 - x0, y1 - y0]) / door.width
    n = np.array([-along[1], along[0]])
    if float(np.dot(n, np.array([x, y]) - door.center)) < 0:
        n = -n  # n points into the start side
    pre = door.center + 40.0 * n
    state = {"phase": 0}

    def policy(e):
        p = np.array([e.sim.x, e.sim.y])
        lateral = float(np.dot(p - door.center, along))
        depth = float(np.dot(p - door.center, n))
        if state["phase"] == 0 and (np.linalg.norm(p - pre) < 10.0 or (abs(lateral) < 3.0 and depth < 48.0)):
            state["phase"] = 1
        if state["phase"] == 0:
            return _steer(e.sim.pose, pre)
        if depth < -ROBOT_RADIUS:
            return _steer(e.sim.pose, door.center - 60.0 * n)  # through: keep going
        h = math.radians(e.sim.heading)
        phi = wrap_deg(math.degrees(math.atan2(-n[1], -n[0])) - e.sim.heading)  # to the through direction
        if abs(phi) > 37.5:
            return TURN_LEFT_60 if phi > 0 else TURN_RIGHT_60

        def lateral_after(turn_deg):
            a = h + math.radians(turn_deg)
            return abs(lateral + 12.0 * (math.cos(a) * along[0] + math.sin(a) * along[1]))

        e1 = lateral_after(0.0)
        near_jambs = depth - 12.0 * math.cos(math.radians(phi)) < 14.0
        if abs(phi) <= 20.0 and (e1 <= 4.0 or (e1 < abs(lateral) - 1.5 and (not near_jambs or e1 <= 5.0))):
            return MOVE_FORWARD
        return TURN_LEFT_15 if lateral_after(15.0) + (phi < -5) * 9 < lateral_after(-15.0) + (phi > 5) * 9 \
            else TURN_RIGHT_15

    return _run(env, start, policy, seed)


def _dk_policy(u):
    """The docking teacher's policy (``teach_dk``), a closure over its phase."""
    light = np.asarray(u.layout.light)
    axis = np.asarray(u.layout.charger_approach)
    pre = light + 60.0 * axis
    state = {"phase": 0}

    def policy(e):
        p = np.array([e.sim.x, e.sim.y])
        if e.sim.last_collision.any() and e.sim.last_action != MOVE_BACKWARD:
            state["phase"] = 0
            return MOVE_BACKWARD
        v = p - light
        on_axis = float(np.dot(v, axis)) >= math.cos(math.radians(20.0)) * float(np.linalg.norm(v))
        if state["phase"] == 0 and (np.linalg.norm(p - pre) < 10.0 or on_axis):
            state["phase"] = 1
        if state["phase"] == 0:
            return _steer(e.sim.pose, pre)
        return _steer(e.sim.pose, light, tol=7.5)

    return policy


def teach_dk(env, start, seed: int | None = None) -> list[tuple]:
    """Demonstrate docking from ``start``: reach the charger's approach axis (a point 60 in out, or
    anywhere within 20 deg of the axis), face the light and drive into the charger; back off after a
    collision."""
    return _run(env, start, _dk_policy(env.unwrapped), seed)


GRID = 12.0  # in: the CHG teacher's route grid
ROUTE_CLEARANCE = ROBOT_RADIUS + 8.0  # route points keep the body 8 in off every surface


def _route_field(layout) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Grid points with room to pass, and each one's path length to the docking teacher's start region (Dijkstra
    over 8-neighbour moves between free points): (xs, ys, distance (ny, nx), inf where unreachable or not free)."""
    w, h = layout.size
    xs, ys = np.arange(GRID / 2, w, GRID), np.arange(GRID / 2, h, GRID)
    free = np.array([[layout.room_at(x, y) is not None and layout.clearance(x, y) >= ROUTE_CLEARANCE for x in xs]
                     for y in ys])
    if not free.any():
        raise ValueError(f"layout {layout.name!r} has no place {ROUTE_CLEARANCE:g} in from every surface: the "
                         "recharging teacher has no route")
    goal = np.asarray(layout.light) + 60.0 * np.asarray(layout.charger_approach)
    dist = np.full(free.shape, np.inf)
    gi = min(zip(*np.nonzero(free), strict=True), key=lambda ij: math.hypot(xs[ij[1]] - goal[0], ys[ij[0]] - goal[1]))
    dist[gi] = 0.0
    heap = [(0.0, gi)]
    while heap:
        d, (i, j) = heapq.heappop(heap)
        if d > dist[i, j]:
            continue
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                a, b = i + di, j + dj
                if (di or dj) and 0 <= a < free.shape[0] and 0 <= b < free.shape[1] and free[a, b]:
                    nd = d + GRID * math.hypot(di, dj)
                    if nd < dist[a, b]:
                        dist[a, b] = nd
                        heapq.heappush(heap, (nd, (a, b)))
    return xs, ys, dist


def _clear_line(layout, p, q, margin: float = ROBOT_RADIUS + 2.0) -> bool:
    n = max(2, int(math.hypot(q[0] - p[0], q[1] - p[1]) / 4.0))
    return all(layout.clearance(p[0] + (q[0] - p[0]) * t, p[1] + (q[1] - p[1]) * t) >= margin
               for t in np.linspace(0.0, 1.0, n))


def chg_policy(u):
    """The recharging teacher (R): follow the shortest grid route to the docking region, steering at the farthest
    route point in clear sight (within 4 grid steps); then the docking teacher takes over."""
    xs, ys, dist = _route_field(u.layout)
    dock = _dk_policy(u)
    light, axis = np.asarray(u.layout.light), np.asarray(u.layout.charger_approach)
    state = {"docking": False}

    def policy(e):
        p = np.array([e.sim.x, e.sim.y])
        v = p - light
        near = np.linalg.norm(v) < 90.0 and float(np.dot(v, axis)) > 0
        if state["docking"] or near:
            state["docking"] = True
            return dock(e)
        if e.sim.last_collision.any() and e.sim.last_action != MOVE_BACKWARD:
            return MOVE_BACKWARD
        i, j = int(np.clip(round((p[1] - ys[0]) / GRID), 0, len(ys) - 1)), int(np.clip(
            round((p[0] - xs[0]) / GRID), 0, len(xs) - 1))
        near_pts, r = [], 2
        while not near_pts:  # the nearest route points (further out when the robot is pressed into a corner)
            near_pts = [(a, b) for a in range(i - r, i + r + 1) for b in range(j - r, j + r + 1)
                        if 0 <= a < len(ys) and 0 <= b < len(xs) and np.isfinite(dist[a, b])]
            r += 2
        cur = min(near_pts, key=lambda ab: (math.hypot(xs[ab[1]] - p[0], ys[ab[0]] - p[1]), dist[ab]))
        target = cur
        for _ in range(4):  # walk down the distance field, keeping the farthest point in clear sight
            a, b = target
            nxt = min(((a + da, b + db) for da in (-1, 0, 1) for db in (-1, 0, 1)
                       if 0 <= a + da < len(ys) and 0 <= b + db < len(xs)), key=lambda ab: dist[ab])
            if dist[nxt] >= dist[target] or not _clear_line(u.layout, p, (xs[nxt[1]], ys[nxt[0]])):
                break
            target = nxt
        return _steer(e.sim.pose, (xs[target[1]], ys[target[0]]), tol=15.0)

    return policy


def teach_chg(env, start, seed: int | None = None) -> list[tuple]:
    """Demonstrate recharging (Ch. 6) from ``start``: route to the charger's docking region, then dock."""
    return _run(env, start, chg_policy(env.unwrapped), seed)


def _nearest_surface(sim: RobotSim) -> np.ndarray:
    segs = sim.layout.segments
    p = np.array([sim.x, sim.y])
    a, b = segs[:, :2], segs[:, 2:]
    e = b - a
    s = np.clip(np.einsum("ij,ij->i", p - a, e) / np.einsum("ij,ij->i", e, e), 0.0, 1.0)
    q = a + s[:, None] * e
    return q[int(np.argmin(np.linalg.norm(q - p, axis=1)))]


def wall_following_action(sim: RobotSim, side: str = "left", target: float = 23.0) -> int:
    """Geometric wall follower: keep the nearest surface on ``side`` at ``target`` in of clearance.

    Heads along the tangent of the nearest surface point, tilted up to 30 deg towards/away from it in
    proportion to the clearance error; turns away when something is close ahead.
    """
    sgn = 1.0 if side == "left" else -1.0
    q = _nearest_surface(sim)
    v = q - np.array([sim.x, sim.y])
    clearance = float(np.linalg.norm(v)) - ROBOT_RADIUS
    tangent = math.degrees(math.atan2(v[1], v[0])) - sgn * 90.0
    tilt = float(np.clip(2.0 * (clearance - target), -30.0, 30.0))
    desired = tangent + sgn * tilt
    ahead = sim.true_ranges()[[22, 23, 0, 1, 2]].min()
    if ahead < 16.0:
        return TURN_RIGHT_60 if side == "left" else TURN_LEFT_60
    return _turn_towards(wrap_deg(desired - sim.heading), tol=10.0)


def teach_wf(env, start, seed: int | None = None) -> list[tuple]:
    """Demonstrate wall following (WFL or WFR, from the env's task) from ``start``."""
    side = "left" if env.unwrapped.task == "WFL" else "right"
    return _run(env, start, lambda e: wall_following_action(e.sim, side), seed)


teach_wfl = teach_wf


def teach(env, start, seed: int | None = None) -> list[tuple]:
    """Scripted demonstration for the env's task (DK, DP, WFL, WFR)."""
    task = env.unwrapped.task
    return {"DK": teach_dk, "DP": teach_dp, "WFL": teach_wf, "WFR": teach_wf}[task](env, start, seed)
