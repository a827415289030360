"""The robot's move and position as compiled kernels, for plays run as one Numba loop (``connrl.tasks.recharge_play``,
``connrl.tasks.robot_play``): ``RobotSim.apply`` after its draw (and with ``sense``), docking and ``Layout.room_at``,
the same arithmetic in the same order, and CPython's ``math.hypot``, which the partial moves divide by (Numba's own
calls libm, whose last bit differs). tests/envs/test_robot_step.py holds them to the Python they mirror.

Not cached: ``_move`` calls the geometry's kernels, and a cached kernel may only call its own file's
(tests/nets/test_kernel_cache.py).
"""

from __future__ import annotations

import functools
import math

import numba
import numpy as np

from connrl.envs.robot.constants import (
    _RNG_PER_SCAN,
    ACTION_MOVE_IN,
    ACTION_TURN_DEG,
    CONTROL_ERROR,
    MOVE_FORWARD,
    ROBOT_RADIUS,
    SEG_CHARGER,
)
from connrl.envs.robot.geometry import _scan, _time_of_impact
from connrl.envs.robot.sim import CONTACT_GAP

_TURN = np.array(ACTION_TURN_DEG)
_MOVE = np.array(ACTION_MOVE_IN)


@numba.njit(cache=False)
def _dl_mul(x, y):
    """Dekker's exact product: hi + lo = x * y (CPython's ``dl_mul``)."""
    t = x * 134217729.0
    xh = t - (t - x)
    xl = x - xh
    t = y * 134217729.0
    yh = t - (t - y)
    yl = y - yh
    hi = x * y
    return hi, xh * yh - hi + xh * yl + xl * yh + xl * yl


@numba.njit(cache=False)
def _hypot(a, b):
    """``math.hypot(a, b)`` for finite a, b, as CPython 3.12 writes its ``vector_norm`` (lossless scaling, squaring
    and summing, then a square root with one differential correction); older versions write it differently, so
    ``hypot_matches`` checks the running interpreter. Numba's own hypot calls libm, whose last bit differs."""
    a, b = abs(a), abs(b)
    m = max(a, b)
    if m == 0.0:
        return m
    _, e = math.frexp(m)
    if e < -1023:
        return math.hypot(a, b)  # subnormal (libm's, not CPython's): a robot's move is never this small
    scale = math.ldexp(1.0, -e)
    csum, frac1, frac2 = 1.0, 0.0, 0.0
    for v in (a, b):
        hi, lo = _dl_mul(v * scale, v * scale)
        s = csum + hi
        frac2 += (csum - s) + hi
        csum = s
        frac1 += lo
    h = math.sqrt(csum - 1.0 + (frac1 + frac2))
    hi, lo = _dl_mul(-h, h)
    s = csum + hi
    frac2 += (csum - s) + hi
    csum = s
    frac1 += lo
    x = csum - 1.0 + (frac1 + frac2)
    h += x / (2.0 * h)
    return h / scale


@functools.cache
def hypot_matches() -> bool:
    """Whether ``_hypot`` is this interpreter's ``math.hypot``, bit for bit, on 20,000 pairs of move sizes."""
    rng = np.random.default_rng(45)
    pairs = rng.normal(0.0, 12.0, (20_000, 2)) * rng.choice([1.0, 1e-3, 1e3], (20_000, 2))
    return all(_hypot(a, b) == math.hypot(a, b) for a, b in pairs.tolist())


@numba.njit(cache=False)
def _move(pose, action, u, control_noise, step_scale, partial, segs, kinds, collision):
    """``RobotSim.apply`` after its draw ``u``: moves ``pose`` (x, y, heading), sets ``collision`` (front, back, left,
    right); returns (collided, the kind of surface touched, the contact's direction from the heading)."""
    scale = (1.0 - CONTROL_ERROR + 2.0 * CONTROL_ERROR * u if control_noise else 1.0) * step_scale
    for k in range(4):
        collision[k] = 0
    turn = _TURN[action]
    if turn != 0.0:
        pose[2] = (pose[2] + turn * scale) % 360.0
        return False, -1, np.nan
    length = _MOVE[action] * scale
    h = math.radians(pose[2])
    dx, dy = length * math.cos(h), length * math.sin(h)
    t, cx, cy, i = _time_of_impact(pose[0], pose[1], dx, dy, segs, ROBOT_RADIUS)
    if t > 1.0:
        pose[0] += dx
        pose[1] += dy
        return False, -1, np.nan
    px, py = pose[0] + t * dx, pose[1] + t * dy
    if partial:
        gap = CONTACT_GAP / _hypot(dx, dy)
        back = gap if gap < t else t
        pose[0], pose[1] = pose[0] + (t - back) * dx, pose[1] + (t - back) * dy
    rel = (math.degrees(math.atan2(cy - py, cx - px)) - pose[2] + 180.0) % 360.0 - 180.0  # sim.wrap_deg
    if rel == -180.0:
        rel = 180.0
    a = abs(rel)
    side = 0 if a <= 45.0 else 1 if a >= 135.0 else 2 if rel > 0 else 3  # FRONT, BACK, LEFT, RIGHT
    collision[side] = 1
    return True, kinds[i], rel


@numba.njit(cache=False)
def _act_and_sense(pose, a, rng, collision, segs, kinds, lights, control_noise, sensor_noise, step_scale, partial,
                   sonar_radius, edge_jump, edge_both, ranges, sonar, light, door):
    """``RobotSim.apply(a)`` then ``RobotSim.sense()``, with their draws from ``rng`` (one, then 26): moves ``pose``,
    sets ``collision`` and the sweep's arrays; returns ``_move``'s (collided, kind, contact direction)."""
    collided, kind, rel = _move(pose, a, rng.random(), control_noise, step_scale, partial, segs, kinds, collision)
    u = rng.random(_RNG_PER_SCAN)
    _scan(pose[0], pose[1], pose[2], segs, kinds, lights[0], lights[1], ROBOT_RADIUS, sonar_radius, u, sensor_noise,
          edge_jump, edge_both, ranges, sonar, light, door)
    return collided, kind, rel


@numba.njit(cache=False)
def _docked(collided, a, kind, rel, dock_tolerance):
    """Docking, as DK and CHG score it: a forward move stopped head-on by the charger box."""
    return collided and a == MOVE_FORWARD and kind == SEG_CHARGER and abs(rel) <= dock_tolerance


def leave(world, pose, collision, action: int, steps: int, trace) -> None:
    """Leave a world (``RobotTaskEnv`` or ``RechargeEnv``) and its simulator as the steps of a compiled play would:
    the pose, the last action's collision bits, the step count and the poses visited."""
    sim = world.sim
    sim.x, sim.y, sim.heading = (float(v) for v in pose)
    sim.last_collision, sim.last_action = collision, int(action)
    world._steps, world._trace = steps, [tuple(p) for p in trace[:steps + 1].tolist()]


@numba.njit(cache=False)
def _room(x, y, rooms):
    """``Layout.room_at`` as the index of its room (the first whose rectangle holds the point), or -1."""
    for r in range(rooms.shape[0]):
        if rooms[r, 0] <= x < rooms[r, 2] and rooms[r, 1] <= y < rooms[r, 3]:
            return r
    return -1


def room_table(layout) -> np.ndarray:
    """``layout.rooms`` as ``_room`` reads them: one row (xmin, ymin, xmax, ymax) per room, in the layout's order."""
    return np.array(list(layout.rooms.values()), dtype=np.float64).reshape(-1, 4)
