"""``RechargeEnv``: the battery-recharging task CHG of thesis Ch. 6 on the HEROINE simulator (6.4).

Description:
    Find the charger and dock on it, starting anywhere in rooms A, B or C with any heading (5.2.2, 6.4). Docking
    is DK's success (a forward move stopped head-on by the charger box, the contact within ``dock_tolerance`` of
    the heading). The primitive actions are Ch. 5's six. This module is the world only: the behaviour-level task
    (actions = the learned behaviours DK, DP, WFL, WFR, one primitive step of the chosen one per step, 6.5) needs
    learned policies and lives in :mod:`connrl.tasks.recharge`.

Observation (``obs="high"`` or ``"flat"``):
    - "high" (16, 6.4.2, :func:`high_level_inputs`): 8 sonar units in *global* coordinates (unit j averages the
      readings whose direction lies within +-22.5 deg of compass bearing 90 + 45 j deg, i.e. north first, then
      counter-clockwise, encoded as Ch. 5's sonar), 3 bits (any collision, any light, any door edge), 3 room bits
      (A, B, C), 2 X-Y units (``xy_scale`` times (x / width - 0.5, y / height - 0.5)). With ``xy=False`` (Ch. 8,
      8.1) the 14 units without the X-Y pair: the doorways from room C into A and into B then look nearly alike (a
      hidden state).
    - "flat" (100, Exp. 1, 6.6.1): every elementary input once -- 24 robot-centred sonar, 24 light, 24 door-edge,
      4 collision, 2 parallelism, 6 clearance bits -- then the 16 (``xy=False``: 14) high-level units. The thesis
      counts 102; it does not list them, and ours holds each input once.
    ``info["task_obs"]`` always carries the four elementary observations of the same scan (DK, DP, WFL, WFR: Ch. 5's
    encodings), so behaviours can act on their own inputs.

Rewards (6.4): ``success_reward`` (+100; Experiment 4's 500) on docking, else 0; ``collision_penalty`` (default 0:
none in Exps 2-5; 6.6.1 also tried -5 and -10 for Exp. 1) is added on each collision.

Starting State: a room drawn uniformly from A, B, C (or ``start_room``), a free position uniform in it, any heading.

Episode End: ``terminated`` on docking; ``truncated`` after ``max_steps`` (200, 6.6) primitive steps.

``step_scale`` shrinks every primitive action (Experiment 4, 6.6.4: one fifth, "the robot could move 12 inches
forward in a single step, while here it could only move 2.4 inches"; turns shrink alike).

``xy=False`` drops the 2 X-Y units (Ch. 8, 8.1); ``xy_scale`` (default 1: each in +-0.5) stretches them, as the
behaviour-level learners' parameters do (Exps 2-5, Ch. 8 with X-Y: 8; docs/RECONSTRUCTION.md, "High-level
learner"); ``layout="changed"`` is 8.4's changed environment.

Differences from the thesis: the X-Y scaling, the global sonar sectors, the uniform choice of start room and the
flat input's size (100, not 102) are ours (docs/RECONSTRUCTION.md, "Recharging (Ch. 6)").
"""

from __future__ import annotations

import math

import gymnasium as gym
import numba as nb
import numpy as np
from gymnasium import spaces

from connrl.envs.robot.constants import DOOR_EDGE_JUMP, MOVE_FORWARD, N_ACTIONS, ROBOT_RADIUS, SEG_CHARGER, SONAR_MAX
from connrl.envs.robot.layout import Layout
from connrl.envs.robot.sim import Reading, RobotSim
from connrl.envs.robot.tasks import R_SUCCESS, _fill_obs, _rejection, _side_features, _uniform_heading

ROOMS = ("A", "B", "C")
HIGH_SIZE = 16
HIGH_SIZE_NO_XY = 14  # Ch. 8 (8.1): the high-level inputs without X-Y
FLAT_SIZE = 24 + 24 + 24 + 4 + 2 + 6 + HIGH_SIZE
BEHAVIOUR_TASKS = ("DK", "DP", "WFL", "WFR")


def global_sonar(sonar: np.ndarray, heading: float) -> np.ndarray:
    """8 averaged readings in global coordinates: unit j averages the rays pointing within [-22.5, 22.5) deg of
    bearing 90 + 45 j (north, north-west, west, ...), whatever the robot's heading (6.4.2)."""
    bearings = (heading + 15.0 * np.arange(sonar.size)) % 360.0
    sector = np.floor(((bearings - 90.0 + 22.5) % 360.0) / 45.0).astype(int)
    return np.bincount(sector, weights=sonar, minlength=8) / np.bincount(sector, minlength=8)


@nb.njit(cache=True)
def _scan_units(sonar, heading, collision, light, door_edge, low, high, sonar_max, out):
    """Hot-path twin of units 0-10 (module docstring): ``encode_sonar(global_sonar(sonar, heading))``, the same
    arithmetic in the same order (tests/envs/test_robot_recharge.py compares them), then the three bits.
    ``sonar_max`` is an argument, not the imported constant: a cached kernel would not see that constant change."""
    sums, counts = np.zeros(8), np.zeros(8)
    for k in range(sonar.size):
        bearing = (heading + 15.0 * k) % 360.0
        j = int(math.floor(((bearing - 90.0 + 22.5) % 360.0) / 45.0))
        sums[j] += sonar[k]
        counts[j] += 1.0
    for j in range(8):
        r = min(max(sums[j] / counts[j], 0.0), sonar_max)
        out[j] = 1.0 - r / 64.0 if r <= 64.0 else -0.25 * (r - 64.0) / (sonar_max - 64.0)
    out[8] = high if collision.any() else low
    out[9] = high if light.any() else low
    out[10] = high if door_edge.any() else low


def high_level_inputs(rd: Reading, x: float, y: float, layout: Layout, low: float = -0.5,
                      xy: bool = True, xy_scale: float = 1.0) -> np.ndarray:
    """The 16 units of 6.4.2 from one scan and the position, or the first 14 without X-Y (module docstring)."""
    high = low + 1.0
    w, h = layout.size
    out = np.empty(HIGH_SIZE, dtype=np.float32)
    _scan_units(rd.sonar, float(rd.compass), rd.collision, rd.light, rd.door_edge, low, high, SONAR_MAX, out)
    out[11:14] = [high if rd.room == r else low for r in ROOMS]
    out[14:16] = [xy_scale * (x / w - 0.5), xy_scale * (y / h - 0.5)]
    return out if xy else out[:HIGH_SIZE_NO_XY].copy()


def task_observations(rd: Reading, low: float = -0.5) -> dict[str, np.ndarray]:
    """Ch. 5's observation of each elementary task from one scan (WFL and WFR share theirs, as in Ch. 5)."""
    high, feat = low + 1.0, np.zeros(4)
    dk, dp, wf = np.empty(52, np.float32), np.empty(52, np.float32), np.empty(36, np.float32)
    _fill_obs(0, rd.sonar, rd.light, rd.collision, low, high, feat, dk)
    _fill_obs(0, rd.sonar, rd.door_edge, rd.collision, low, high, feat, dp)
    _side_features(rd.body_sonar(), ROBOT_RADIUS, feat)  # body clearances (5.3.1)
    _fill_obs(1, rd.sonar, rd.light, rd.collision, low, high, feat, wf)
    return {"DK": dk, "DP": dp, "WFL": wf, "WFR": wf.copy()}


def sample_in_room(rng: np.random.Generator, layout: Layout, room: str) -> tuple[float, float, float]:
    """A free position uniform in ``room`` (rejection), any heading."""
    x0, y0, x1, y1 = layout.rooms[room]

    def sample():
        return (float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1)))

    x, y = _rejection(rng, sample, lambda p: layout.room_at(*p) == room and layout.is_free(*p), f"room {room}")
    return (x, y, _uniform_heading(rng))


class RechargeEnv(gym.Env):
    """CHG: dock on the charger from anywhere (see the module docstring)."""

    metadata = {"render_modes": [], "render_fps": 4}

    def __init__(self, layout: Layout | str = "default", obs: str = "high", max_steps: int = 200,
                 start_room: str | None = None, collision_penalty: float = 0.0, dock_tolerance: float = 30.0,
                 binary_low: float = -0.5, edge_jump: float = DOOR_EDGE_JUMP, noise: bool = True,
                 step_scale: float = 1.0, success_reward: float = R_SUCCESS, xy: bool = True,
                 xy_scale: float = 1.0):
        if obs not in ("high", "flat"):
            raise ValueError(f"obs must be 'high' (16 units, 6.4.2) or 'flat' (100, Exp. 1), got {obs!r}")
        if start_room is not None and start_room not in ROOMS:
            raise ValueError(f"start_room must be None (any) or one of {ROOMS}, got {start_room!r}")
        if int(max_steps) != max_steps or max_steps < 1:
            raise ValueError(f"max_steps must be a positive integer, got {max_steps!r}")
        if not (math.isfinite(collision_penalty) and collision_penalty <= 0):
            raise ValueError(f"collision_penalty must be a finite number <= 0, got {collision_penalty!r}")
        if not (math.isfinite(success_reward) and success_reward > 0):
            raise ValueError(f"success_reward must be a finite number > 0, got {success_reward!r}")
        if not isinstance(xy, bool):
            raise ValueError(f"xy must be True (X-Y inputs, Ch. 6) or False (none, Ch. 8), got {xy!r}")
        if isinstance(xy_scale, bool) or not isinstance(xy_scale, (int, float)) or not (
                math.isfinite(xy_scale) and xy_scale > 0):
            raise ValueError(f"xy_scale must be a finite number > 0, got {xy_scale!r}")
        self.success_reward, self.xy, self.xy_scale = float(success_reward), xy, float(xy_scale)
        self.layout = layout if isinstance(layout, Layout) else Layout.load(layout)
        self.obs_mode, self.max_steps, self.start_room = obs, int(max_steps), start_room
        self.collision_penalty, self.dock_tolerance = float(collision_penalty), float(dock_tolerance)
        self.binary_low = float(binary_low)
        self.sim = RobotSim(self.layout, np.random.default_rng(), sensor_noise=noise, control_noise=noise,
                            edge_jump=edge_jump, step_scale=step_scale)
        n = (HIGH_SIZE if obs == "high" else FLAT_SIZE) - (0 if xy else HIGH_SIZE - HIGH_SIZE_NO_XY)
        lo, hi = min(self.binary_low, -0.5), max(self.binary_low + 1.0, 1.0)
        low, high = np.full(n, lo, np.float32), np.full(n, hi, np.float32)
        if xy:  # the X-Y pair closes the high-level inputs (and so the flat ones)
            low[-2:], high[-2:] = min(lo, -self.xy_scale / 2), max(hi, self.xy_scale / 2)
        self.observation_space = spaces.Box(low, high, dtype=np.float32)
        self.action_space = spaces.Discrete(N_ACTIONS)
        self._steps, self._room0, self._trace = 0, None, []

    def sample_start(self, rng: np.random.Generator | None = None, room: str | None = None) -> tuple:
        """A start pose: in ``room`` (else the env's ``start_room``, else a room drawn uniformly)."""
        rng = self.np_random if rng is None else rng
        room = room or self.start_room or ROOMS[int(rng.integers(len(ROOMS)))]
        return sample_in_room(rng, self.layout, room)

    def _observe(self, rd: Reading):
        x, y, _ = self.sim.pose
        top = high_level_inputs(rd, x, y, self.layout, self.binary_low, self.xy, self.xy_scale)
        tasks = task_observations(rd, self.binary_low)
        if self.obs_mode == "high":
            return top, tasks
        flat = np.concatenate([tasks["DK"][:48], tasks["DP"][24:48], tasks["DK"][48:52], tasks["WFL"][28:36], top])
        return flat.astype(np.float32), tasks

    def _info(self, rd: Reading, tasks, success=False, collision=False) -> dict:
        return {"pose": self.sim.pose, "room": rd.room, "start_room": self._room0, "success": bool(success),
                "collision": bool(collision), "compass": rd.compass, "task_obs": tasks}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.sim.rng = self.np_random
        options = dict(options or {})
        unknown = set(options) - {"start", "room"}
        if unknown:
            raise ValueError(f"unknown reset options {sorted(unknown)}; allowed: ['room', 'start']")
        start = options.get("start") or self.sample_start(room=options.get("room"))
        self.sim.place(*start)
        self._steps, self._room0, self._trace = 0, self.sim.room, [self.sim.pose]
        rd = self.sim.sense()
        obs, tasks = self._observe(rd)
        return obs, self._info(rd, tasks)

    def step(self, action):
        a = int(action)
        if a != action or not 0 <= a < N_ACTIONS:
            raise ValueError(f"action must be in 0..{N_ACTIONS - 1}, got {action!r}")
        m = self.sim.apply(a)
        rd = self.sim.sense()
        self._steps += 1
        docked = (m.collided and a == MOVE_FORWARD and m.contact_kind == SEG_CHARGER
                  and abs(m.contact_angle) <= self.dock_tolerance)
        reward = self.success_reward if docked else (self.collision_penalty if m.collided else 0.0)
        self._trace.append(self.sim.pose)
        obs, tasks = self._observe(rd)
        truncated = not docked and self._steps >= self.max_steps
        return obs, float(reward), bool(docked), truncated, self._info(rd, tasks, docked, m.collided)

    @property
    def trace(self) -> list[tuple[float, float, float]]:
        """Poses visited in the current trial (start included), for path figures."""
        return list(self._trace)
