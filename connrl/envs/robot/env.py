"""``RobotTaskEnv``: the elementary tasks DK, DP, WFL, WFR as one Gymnasium environment (the full description is
the docstring of ``connrl.envs.robot.tasks``)."""

from __future__ import annotations

import math
from collections.abc import Callable

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from connrl.envs.robot.constants import (
    ACTION_NAMES,
    COLLISION,
    COLLISION_SIDES,
    DOOR_EDGE_JUMP,
    DP_FAR,
    EDGE_MARK,
    MOVE_BACKWARD,
    MOVE_FORWARD,
    N_ACTIONS,
    PASS_DEPTH,
    ROBOT_RADIUS,
    SEG_CHARGER,
    SONAR_ORIGIN,
)
from connrl.envs.robot.layout import Layout
from connrl.envs.robot.render import HumanViewer, render_frame
from connrl.envs.robot.sim import Reading, RobotSim
from connrl.envs.robot.tasks import (
    CLEARANCE_MAX,
    CLEARANCE_MIN,
    OBS_SIZE,
    R_BACKWARD,
    R_COLLISION,
    R_SUCCESS,
    TASKS,
    WF_PARALLEL_DEG,
    WF_REWARDS,
    _fill_obs,
    _side_features,
    sample_anywhere,
    sample_dk_start,
    sample_dp_start,
)


# ---------------------------------------------------------------------------------------------------
class RobotTaskEnv(gym.Env):
    """One elementary HEROINE task (DK, DP, WFL or WFR); see the module docstring."""

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 4}

    def __init__(self, task: str = "DK", layout: Layout | str = "default", binary_low: float = -0.5,
                 max_steps: int = 30, render_mode: str | None = None, noise: bool = True,
                 sensor_noise: bool | None = None, control_noise: bool | None = None,
                 start_sampler: Callable[[np.random.Generator, Layout], tuple] | None = None,
                 dk_radius: float = 96.0, dp_offset: float | None = None,
                 dp_depth: tuple[float, float] = (24.0, DP_FAR), dp_heading: float = 180.0,
                 dock_tolerance: float = 30.0, pass_depth: float = PASS_DEPTH, render_rays: bool = False,
                 edge_jump: float = DOOR_EDGE_JUMP, sonar_origin: str = SONAR_ORIGIN, collision: str = COLLISION,
                 edge_mark: str = EDGE_MARK):
        if task not in TASKS:
            raise ValueError(f"task must be one of {TASKS}, got {task!r}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or one of {self.metadata['render_modes']}, "
                             f"got {render_mode!r}")
        if int(max_steps) != max_steps or max_steps < 1:
            raise ValueError(f"max_steps must be a positive integer, got {max_steps!r}")
        if not math.isfinite(binary_low):
            raise ValueError(f"binary_low must be a finite number, got {binary_low!r}")
        self.task = task
        self.layout = layout if isinstance(layout, Layout) else Layout.load(layout)
        self.binary_low = float(binary_low)
        # "on" is one unit above "off": -0.5/+0.5 (5.3.2) by default, 0/1 with binary_low=0 (5.4.4).
        self.binary_high = self.binary_low + 1.0
        self.max_steps = int(max_steps)
        self.render_mode = render_mode
        self.render_rays = bool(render_rays)
        self.dock_tolerance = float(dock_tolerance)
        if not pass_depth >= 0:
            raise ValueError(f"pass_depth must be >= 0 inches, got {pass_depth!r}")
        self.pass_depth = float(pass_depth)
        self._start_sampler = start_sampler
        self._dk_radius, self._dp_depth = float(dk_radius), tuple(float(v) for v in dp_depth)
        self._dp_offset = None if dp_offset is None else float(dp_offset)
        if not 0 <= dp_heading <= 180:
            raise ValueError(f"dp_heading must be 0..180 deg (spread about facing the door), got {dp_heading!r}")
        self._dp_heading = float(dp_heading)
        sn = noise if sensor_noise is None else sensor_noise
        cn = noise if control_noise is None else control_noise
        self.sim = RobotSim(self.layout, np.random.default_rng(), sensor_noise=sn, control_noise=cn,
                            edge_jump=edge_jump, sonar_origin=sonar_origin, collision=collision, edge_mark=edge_mark)

        n = OBS_SIZE[task]
        lo = np.full(n, min(self.binary_low, -0.25), dtype=np.float32)
        hi = np.full(n, max(self.binary_high, 1.0), dtype=np.float32)
        lo[:24], hi[:24] = -0.25, 1.0
        lo[24:], hi[24:] = self.binary_low, self.binary_high
        if task in ("WFL", "WFR"):
            lo[28:30], hi[28:30] = -0.5, 0.5
        self.observation_space = spaces.Box(lo, hi, dtype=np.float32)
        self.action_space = spaces.Discrete(N_ACTIONS)

        self._feat, self._feat_true = np.zeros(4), np.zeros(4)
        self._steps = 0
        self._start_room: str | None = None
        self._reading: Reading | None = None
        self._trace: list[tuple[float, float, float]] = []
        self._viewer: HumanViewer | None = None

    # -- tasks --------------------------------------------------------------------------------------
    def sample_task(self, rng: np.random.Generator | None = None) -> tuple[float, float, float]:
        """A start pose (x, y, heading) from this task's start generator; fix 50 for a run's tests."""
        rng = self.np_random if rng is None else rng
        if self._start_sampler is not None:
            return tuple(float(v) for v in self._start_sampler(rng, self.layout))
        if self.task == "DK":
            return sample_dk_start(rng, self.layout, self._dk_radius)
        if self.task == "DP":
            return sample_dp_start(rng, self.layout, self._dp_offset, self._dp_depth, self._dp_heading)
        return sample_anywhere(rng, self.layout)

    # -- observation --------------------------------------------------------------------------------
    def _observe(self, rd: Reading) -> np.ndarray:
        out = np.empty(self.observation_space.shape[0], dtype=np.float32)
        if self.task in ("WFL", "WFR"):
            _side_features(rd.body_sonar(), ROBOT_RADIUS, self._feat)  # body clearances (5.3.1)
            _fill_obs(1, rd.sonar, rd.light, rd.collision, self.binary_low, self.binary_high, self._feat, out)
        else:
            bits = rd.light if self.task == "DK" else rd.door_edge
            _fill_obs(0, rd.sonar, bits, rd.collision, self.binary_low, self.binary_high, self._feat, out)
        return out

    def _info(self, room, success=False, collision=False, side=-1) -> dict:
        x, y, h = self.sim.pose
        return {"pose": (x, y, h), "success": bool(success), "collision": bool(collision),
                "collision_side": COLLISION_SIDES[side] if side >= 0 else None, "room": room, "compass": h}

    # -- gym API ------------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.sim.rng = self.np_random
        options = options or {}
        unknown = set(options) - {"start"}
        if unknown:
            raise ValueError(f"unknown reset options {sorted(unknown)}; allowed: ['start']")
        start = options.get("start")
        if start is None:
            start = self.sample_task()
        elif len(start) != 3:
            raise ValueError(f"options['start'] must be (x, y, heading_deg), got {start!r}")
        self.sim.place(*start)
        self._steps = 0
        self._start_room = self.sim.room
        self._reading = self.sim.sense()
        self._trace = [self.sim.pose]
        if self.render_mode == "human":
            self.render()
        return self._observe(self._reading), self._info(self._reading.room)

    def step(self, action):
        if self._reading is None:
            raise RuntimeError("call reset() before step()")
        a = int(action)
        if a != action or not 0 <= a < N_ACTIONS:
            raise ValueError(f"action must be in 0..{N_ACTIONS - 1} {ACTION_NAMES}, got {action!r}")
        m = self.sim.apply(a)
        rd = self.sim.sense()
        self._reading = rd
        self._steps += 1
        success = False
        if self.task == "DK":
            success = (m.collided and a == MOVE_FORWARD and m.contact_kind == SEG_CHARGER
                       and abs(m.contact_angle) <= self.dock_tolerance)
            reward = R_SUCCESS if success else (R_COLLISION if m.collided else 0.0)
        elif self.task == "DP":
            # a move that touches a jamb scores the collision even if it ends in the other room (moves stopped at
            # the contact can); the pass is then scored on the next step
            success = not m.collided and self._passed_door(rd.room)
            reward = R_SUCCESS if success else (R_COLLISION if m.collided else 0.0)
        else:
            reward = self._wf_reward(a, m.collided, rd.ranges)
        self._trace.append(self.sim.pose)
        terminated = bool(success)
        truncated = (not terminated) and self._steps >= self.max_steps
        if self.render_mode == "human":
            self.render()
        return self._observe(rd), float(reward), terminated, truncated, self._info(rd.room, success,
                                                                                   m.collided, m.side)

    def _wf_reward(self, a: int, collided: bool, ranges: np.ndarray) -> float:
        """wall_following_reward on the compiled side features (same rules, same numbers)."""
        if collided:
            return R_COLLISION
        if a == MOVE_BACKWARD:
            return R_BACKWARD
        f = self._feat_true
        _side_features(ranges, ROBOT_RADIUS, f)
        j = 0 if self.task == "WFL" else 1
        if min(f[2], f[3]) < CLEARANCE_MIN or f[2 + j] > CLEARANCE_MAX or a != MOVE_FORWARD:
            return 0.0
        al = abs(f[j])
        return WF_REWARDS[0] if al <= WF_PARALLEL_DEG[0] else WF_REWARDS[1] if al <= WF_PARALLEL_DEG[1] \
            else WF_REWARDS[2]

    def _passed_door(self, room) -> bool:
        if room is None or room == self._start_room:
            return False
        if self.pass_depth <= 0.0:
            return True  # "getting into another room" (6.5)
        x, y = self.sim.x, self.sim.y
        for d in self.layout.doors.values():
            x0, y0, x1, y1 = d.segment
            ex, ey = x1 - x0, y1 - y0
            s = min(1.0, max(0.0, ((x - x0) * ex + (y - y0) * ey) / (ex * ex + ey * ey)))
            if math.hypot(x0 + s * ex - x, y0 + s * ey - y) < self.pass_depth:
                return False
        return True

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' or 'human'")
            return None
        img = render_frame(self.layout, self.sim.pose, reading=self._reading, rays=self.render_rays,
                           trace=[p[:2] for p in self._trace], title=f"{self.task}  step {self._steps}")
        if self.render_mode == "rgb_array":
            return img
        if self._viewer is None:
            self._viewer = HumanViewer()
        self._viewer.show(img, self.metadata["render_fps"])
        return None

    def close(self):
        if self._viewer is not None:
            self._viewer.close()
            self._viewer = None

    @property
    def trace(self) -> list[tuple[float, float, float]]:
        """Poses visited in the current trial (start included), for path figures."""
        return list(self._trace)


