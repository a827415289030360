"""The robot simulator: compiled ray casting and collision kernels, and ``RobotSim`` (motion, sensing)."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from connrl.envs.robot.constants import (
    _RNG_PER_SCAN,
    ACTION_MOVE_IN,
    ACTION_NAMES,
    ACTION_TURN_DEG,
    BACK,
    COLLISION,
    CONTROL_ERROR,
    DOOR_EDGE_JUMP,
    EDGE_MARK,
    FRONT,
    LEFT,
    N_ACTIONS,
    N_RAYS,
    RIGHT,
    ROBOT_RADIUS,
    SONAR_ORIGIN,
)
from connrl.envs.robot.geometry import _cast_rays, _scan, _time_of_impact
from connrl.envs.robot.layout import Layout

SONAR_ORIGINS = ("body", "centre")
COLLISIONS = ("cancel", "partial")
EDGE_MARKS = ("nearer", "both")
CONTACT_GAP = 1e-3  # in: a partial move stops this short of the surface


# ---------------------------------------------------------------------------------------------------
# Simulator
class Motion(NamedTuple):
    """Outcome of one action."""

    action: int
    collided: bool  # the move touched a surface (cancelled, or stopped at the contact)
    side: int  # collision side (FRONT/BACK/LEFT/RIGHT) or -1
    contact_kind: int  # SEG_* kind of the surface touched, or -1
    contact_angle: float  # contact direction relative to the heading, degrees in (-180, 180]; nan if none


class Reading(NamedTuple):
    """One sensor sweep, robot-centred (index k is the direction heading + 15k deg)."""

    sonar: np.ndarray  # (24,) float, noisy readings 0..127 in
    ranges: np.ndarray  # (24,) float, noise-free body distances clipped to 127 (for reward functions)
    light: np.ndarray  # (24,) uint8 light bits
    door_edge: np.ndarray  # (24,) uint8 door-edge bits
    collision: np.ndarray  # (4,) uint8 (front, back, left, right)
    compass: float  # heading, degrees in [0, 360)
    room: str | None
    sonar_radius: float = ROBOT_RADIUS  # the sonar reads from this far off the centre (the body's radius, or 0)

    def body_sonar(self) -> np.ndarray:
        """The sonar readings as distances from the body surface (5.3.1's clearances), whatever their origin."""
        return self.sonar if self.sonar_radius == ROBOT_RADIUS else self.sonar - (ROBOT_RADIUS - self.sonar_radius)


def wrap_deg(a: float) -> float:
    """Angle in degrees wrapped to (-180, 180]."""
    a = (a + 180.0) % 360.0 - 180.0
    return 180.0 if a == -180.0 else a


class RobotSim:
    """The HEROINE robot in a :class:`Layout`: pose, actions with control error, sensors.

    Args:
        layout: a :class:`Layout` or the name of a shipped layout.
        rng: the Generator all noise is drawn from (replace ``sim.rng`` to re-seed).
        sensor_noise: sonar noise and dropouts on (5.2.1). Off gives exact readings.
        control_noise: 8% control error on (5.2.1). Off gives exact 15/60 deg and 12 in.
        edge_jump: neighbouring sonar readings differing by at least this many inches mark a door edge (R).
        step_scale: every turn and move is this fraction of its size (Ch. 6's Experiment 4: 1/5).
        sonar_origin: sonar distances from the "body" surface or the robot's "centre" (R; issue 44's family).
        collision: a move that would touch is "cancel"led, or made "partial"ly up to the contact (R; issue 44).
        edge_mark: a door-edge jump marks the "nearer" reading or "both" readings (R; issue 44).
    """

    def __init__(self, layout: Layout | str = "default", rng: np.random.Generator | None = None, *,
                 sensor_noise: bool = True, control_noise: bool = True, edge_jump: float = DOOR_EDGE_JUMP,
                 step_scale: float = 1.0, sonar_origin: str = SONAR_ORIGIN, collision: str = COLLISION,
                 edge_mark: str = EDGE_MARK):
        if not 0 < edge_jump < math.inf:
            raise ValueError(f"edge_jump must be a finite number of inches > 0, got {edge_jump!r}")
        if not 0 < step_scale <= 1:
            raise ValueError(f"step_scale must be in (0, 1] (a fraction of the primitive actions), got {step_scale!r}")
        self.step_scale = float(step_scale)
        for name, value, allowed in (("sonar_origin", sonar_origin, SONAR_ORIGINS),
                                     ("collision", collision, COLLISIONS), ("edge_mark", edge_mark, EDGE_MARKS)):
            if value not in allowed:
                raise ValueError(f"{name} must be one of {', '.join(allowed)}, got {value!r}")
        self.sonar_radius = ROBOT_RADIUS if sonar_origin == "body" else 0.0
        self.partial_moves = collision == "partial"
        self.edge_both = edge_mark == "both"
        self.edge_jump = float(edge_jump)
        self.layout = layout if isinstance(layout, Layout) else Layout.load(layout)
        self.rng = rng if rng is not None else np.random.default_rng()
        self.sensor_noise = bool(sensor_noise)
        self.control_noise = bool(control_noise)
        self._segs = self.layout.segments
        self._kinds = self.layout.kinds
        self._light = self.layout.light
        self.x, self.y, self.heading = 0.0, 0.0, 0.0
        self.last_collision = np.zeros(4, dtype=np.uint8)
        self.last_action = -1

    # -- state --------------------------------------------------------------------------------------
    @property
    def pose(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.heading)

    @property
    def room(self) -> str | None:
        return self.layout.room_at(self.x, self.y)

    def place(self, x: float, y: float, heading: float) -> None:
        """Put the robot at a pose; raises ValueError if the disc would overlap a surface or lie outside."""
        x, y, heading = float(x), float(y), float(heading)
        if not all(map(math.isfinite, (x, y, heading))):
            raise ValueError(f"pose must be finite numbers, got {(x, y, heading)}")
        if self.layout.room_at(x, y) is None:
            raise ValueError(f"pose {(x, y)} is outside every room of layout {self.layout.name!r}")
        c = self.layout.clearance(x, y)
        if c < ROBOT_RADIUS:
            raise ValueError(f"a robot of radius {ROBOT_RADIUS} at {(x, y)} overlaps a surface "
                             f"(clearance {c:.1f} in); choose a free pose")
        self.x, self.y, self.heading = x, y, heading % 360.0
        self.last_collision = np.zeros(4, dtype=np.uint8)
        self.last_action = -1

    # -- dynamics -----------------------------------------------------------------------------------
    def apply(self, action: int) -> Motion:
        """Execute one primitive action (see ACTION_NAMES)."""
        if not (0 <= int(action) < N_ACTIONS) or int(action) != action:
            raise ValueError(f"action must be an integer in 0..{N_ACTIONS - 1} {ACTION_NAMES}, "
                             f"got {action!r}")
        action = int(action)
        u = self.rng.random()  # drawn unconditionally: noise on/off keeps the stream aligned
        scale = (1.0 - CONTROL_ERROR + 2.0 * CONTROL_ERROR * u if self.control_noise else 1.0) * self.step_scale
        self.last_collision = np.zeros(4, dtype=np.uint8)
        self.last_action = action
        turn = ACTION_TURN_DEG[action]
        if turn != 0.0:
            self.heading = (self.heading + turn * scale) % 360.0
            return Motion(action, False, -1, -1, float("nan"))
        length = ACTION_MOVE_IN[action] * scale
        h = math.radians(self.heading)
        dx, dy = length * math.cos(h), length * math.sin(h)
        t, cx, cy, i = _time_of_impact(self.x, self.y, dx, dy, self._segs, ROBOT_RADIUS)
        if t > 1.0:
            self.x += dx
            self.y += dy
            return Motion(action, False, -1, -1, float("nan"))
        px, py = self.x + t * dx, self.y + t * dy
        if self.partial_moves:  # up to the contact, a hair short so the disc never overlaps the surface
            back = min(t, CONTACT_GAP / math.hypot(dx, dy))
            self.x, self.y = self.x + (t - back) * dx, self.y + (t - back) * dy
        rel = wrap_deg(math.degrees(math.atan2(cy - py, cx - px)) - self.heading)
        side = collision_side(rel)
        self.last_collision[side] = 1
        return Motion(action, True, side, int(self._kinds[i]), rel)

    # -- sensing ------------------------------------------------------------------------------------
    def sense(self) -> Reading:
        """One sweep of all sensors at the current pose (collision bits from the last action)."""
        u = self.rng.random(_RNG_PER_SCAN)
        ranges, sonar = np.empty(N_RAYS), np.empty(N_RAYS)
        light, door = np.empty(N_RAYS, dtype=np.uint8), np.empty(N_RAYS, dtype=np.uint8)
        _scan(self.x, self.y, self.heading, self._segs, self._kinds, self._light[0], self._light[1],
              ROBOT_RADIUS, self.sonar_radius, u, self.sensor_noise, self.edge_jump, self.edge_both, ranges, sonar,
              light, door)
        return Reading(sonar, ranges, light, door, self.last_collision.copy(), self.heading, self.room,
                       self.sonar_radius)

    def true_ranges(self) -> np.ndarray:
        """Noise-free body distance along each ray, not clipped at 127 (does not consume randomness)."""
        out = np.empty(N_RAYS)
        _cast_rays(self.x, self.y, self.heading, self._segs, out)
        return out - ROBOT_RADIUS


def collision_side(rel_deg: float) -> int:
    """Collision bit for a contact at ``rel_deg`` from the heading (front +-45, left 45..135, ...)."""
    a = abs(rel_deg)
    if a <= 45.0:
        return FRONT
    if a >= 135.0:
        return BACK
    return LEFT if rel_deg > 0 else RIGHT


