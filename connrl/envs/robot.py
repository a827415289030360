"""HEROINE, the mobile-robot simulator of thesis Ch. 5 (5.2), used again in Ch. 6 and Ch. 8.

Description:
    A disc robot (radius 12 in) in a three-room office (Fig. 5.3): rooms A (south-west) and B
    (south-east) open through two 36-in doorways onto room C (a strip along the north wall). A battery
    charger with a light on top sits in A's south-west corner. This module holds the world only:
    the :class:`Layout` (plain JSON data under ``connrl/data/layouts/``), the robot's motion with
    control error and collision handling, its sensors (sonar, light, door-edge, collision, compass,
    room), and rendering. The learning tasks built on it are in :mod:`connrl.envs.robot_tasks`.

    Frame: x east, y north, inches; headings in degrees counter-clockwise from east.

Action Space:
    Six primitive actions (5.2.1), in the order the thesis lists them:
    0 turn +15 deg (left), 1 turn -15 deg (right), 2 turn +60 deg (left), 3 turn -60 deg (right),
    4 move +12 in (forward), 5 move -12 in (backward).

Sensors (``RobotSim.sense`` -> :class:`Reading`):
    - sonar: 24 readings, ray ``k`` points at ``heading + 15k`` deg (robot-centred: ray 0 ahead,
      ray 6 left, ray 12 behind, ray 18 right). A reading is the distance from the robot's body
      (disc edge) to the first surface along the ray, times U(0.9, 1.1), rounded to 1 in, clipped to
      0..127. With probability 1/4 per scan one random reading is replaced by 127 (5.2.1).
    - light: 24 bits; bit ``k`` is on when the light lies within +-7.5 deg of ray ``k``, within 120 in
      of the robot's centre, and no wall or obstacle blocks the line of sight (the charger itself
      does not: the light sits on top of it).
    - door edge: 24 bits computed from the (noisy) sonar scan; when two neighbouring readings differ
      by 24 in or more, the bit of the *nearer* reading is set (that is where the edge is).
    - collision: 4 bits in the order (front, back, left, right); set after a move that was
      cancelled, on the side where the body touched: front |angle| <= 45 deg, left 45..135,
      back >= 135, right -135..-45 (angle of the contact point relative to the heading).
    - compass (heading, degrees) and the current room (the room rectangle holding the centre).

Dynamics:
    A turn changes the heading by the nominal angle times U(0.92, 1.08); a move translates the
    centre by the nominal length times U(0.92, 1.08) along the heading (8% control error, 5.2.1).
    Turning never collides (a disc turning in place sweeps nothing). A move whose swept disc would
    touch any wall, obstacle or the charger box is cancelled: the robot stays where it was and the
    collision bit of the side of first contact is set.

Randomness:
    All noise comes from the ``numpy.random.Generator`` handed to :class:`RobotSim`. Every action
    draws a fixed number of variates (1 for control, 26 for a scan) whether or not noise is enabled,
    so switching noise off does not shift the random stream of anything else.

Differences from the thesis:
    - The geometry, the noise model and the door-edge/light rules are reconstructions (SPEC 5, R):
      the thesis's Fig. 5.3 is lost. Walls have zero thickness.
    - Sonar distances are measured from the body surface (disc edge), not from the centre, so that a
      reading of 0 means contact and the wall-following clearance (14-32 in "between its body and
      obstacles", 5.3.1) can be read straight off the sonar; the thesis does not say which.
    - A colliding move is cancelled entirely (the robot does not creep up to the obstacle).
    - Light bits are noise-free; the thesis's ~10% sensing error is applied to the sonar only.
    - The changed layout of 8.4 (``changed.json``) is our reconstruction of the lost Fig. 8.2.
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numba as nb
import numpy as np

from connrl.storage import atomic_write_bytes

# ---------------------------------------------------------------------------------------------------
# Constants of the robot and its sensors (5.2.1; SPEC 5)
ROBOT_RADIUS = 12.0  # inches (Fig. 5.3 caption)
N_RAYS = 24  # sonar / light readings per rotation, 15 deg apart (5.2.1)
RAY_STEP_DEG = 15.0
SONAR_MAX = 127  # sonar range 0..127 in, 1-in resolution (5.2.1)
SONAR_ERROR = 0.10  # reading uniform in [0.9x, 1.1x] (5.2.1)
DROPOUT_PROB = 0.25  # one reading of every 4 scans set to 127 (5.2.1)
CONTROL_ERROR = 0.08  # "about 8% control error" (5.2.1; R: uniform on length and angle)
DOOR_EDGE_JUMP = 24  # neighbouring readings differing by this much mark a potential door edge (R)
LIGHT_HALF_ANGLE = 7.5  # light bit k on when the light is within +-7.5 deg of ray k (R)
LIGHT_RANGE = 120.0  # light detectable up to this distance from the centre (R)

# Actions, in the order of 5.2.1 ("turn +-15, turn +-60, move +-12").
TURN_LEFT_15, TURN_RIGHT_15, TURN_LEFT_60, TURN_RIGHT_60, MOVE_FORWARD, MOVE_BACKWARD = range(6)
N_ACTIONS = 6
ACTION_NAMES = ("turn +15", "turn -15", "turn +60", "turn -60", "move +12", "move -12")
ACTION_TURN_DEG = (15.0, -15.0, 60.0, -60.0, 0.0, 0.0)
ACTION_MOVE_IN = (0.0, 0.0, 0.0, 0.0, 12.0, -12.0)

# Keyboard teaching tool: six keys -> actions (arrow-free so it works in any terminal).
KEYMAP = {
    "a": TURN_LEFT_15,
    "d": TURN_RIGHT_15,
    "q": TURN_LEFT_60,
    "e": TURN_RIGHT_60,
    "w": MOVE_FORWARD,
    "s": MOVE_BACKWARD,
}

# Collision bit order.
FRONT, BACK, LEFT, RIGHT = range(4)
COLLISION_SIDES = ("front", "back", "left", "right")

# Segment kinds.
SEG_WALL, SEG_OBSTACLE, SEG_CHARGER = 0, 1, 2

LAYOUT_DIR = Path(__file__).resolve().parent.parent / "data" / "layouts"

_RNG_PER_SCAN = 26  # 24 sonar noise factors + dropout coin + dropout index


# ---------------------------------------------------------------------------------------------------
# Layout
def _rect(v, what: str) -> tuple[float, float, float, float]:
    if len(v) != 4:
        raise ValueError(f"{what}: expected [xmin, ymin, xmax, ymax], got {v!r}")
    x0, y0, x1, y1 = (float(c) for c in v)
    if not (x1 > x0 and y1 > y0):
        raise ValueError(f"{what}: need xmax > xmin and ymax > ymin, got {v!r}")
    return (x0, y0, x1, y1)


def _rect_segments(r) -> list[tuple[float, float, float, float]]:
    x0, y0, x1, y1 = r
    return [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]


@dataclass(frozen=True)
class Door:
    """A doorway: the opening segment in a wall and the two rooms it joins."""

    name: str
    segment: tuple[float, float, float, float]
    rooms: tuple[str, str]

    @property
    def center(self) -> np.ndarray:
        x0, y0, x1, y1 = self.segment
        return np.array([(x0 + x1) / 2, (y0 + y1) / 2])

    @property
    def width(self) -> float:
        x0, y0, x1, y1 = self.segment
        return math.hypot(x1 - x0, y1 - y0)


@dataclass(frozen=True)
class Layout:
    """The static world: walls, doors, obstacles, rooms, charger and light (plain JSON data).

    Rooms are axis-aligned rectangles ``[xmin, ymin, xmax, ymax]``; walls are segments
    ``[x0, y0, x1, y1]``; obstacles and the charger box are rectangles. ``charger_approach`` is the
    unit direction from the charger towards a robot docking on it (used by the DK teacher).
    ``locations`` (L1..L4 of Fig. 5.3, ``[x, y, heading]``) and ``subgoals`` (Fig. 6.2, ``[x, y]``)
    are named reference points for experiments.
    """

    name: str
    size: tuple[float, float]
    rooms: dict[str, tuple[float, float, float, float]]
    walls: tuple[tuple[float, float, float, float], ...]
    doors: dict[str, Door]
    obstacles: tuple[tuple[float, float, float, float], ...]
    charger: tuple[float, float, float, float]
    light: tuple[float, float]
    charger_approach: tuple[float, float]
    locations: dict[str, tuple[float, ...]]
    subgoals: dict[str, tuple[float, float]]
    description: str = ""

    # -- construction -------------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, d: dict) -> Layout:
        required = ("name", "size", "rooms", "walls", "doors", "obstacles", "charger")
        missing = [k for k in required if k not in d]
        if missing:
            raise ValueError(f"layout is missing keys {missing}; required keys are {list(required)}")
        rooms = {str(k): _rect(v, f"room {k!r}") for k, v in d["rooms"].items()}
        walls = []
        for i, w in enumerate(d["walls"]):
            if len(w) != 4:
                raise ValueError(f"wall {i}: expected [x0, y0, x1, y1], got {w!r}")
            walls.append(tuple(float(c) for c in w))
        doors = {}
        for k, v in d["doors"].items():
            seg = tuple(float(c) for c in v["segment"])
            rs = tuple(v["rooms"])
            if len(seg) != 4 or len(rs) != 2 or any(r not in rooms for r in rs):
                raise ValueError(f"door {k!r}: need 'segment' [x0,y0,x1,y1] and two known 'rooms', got {v!r}")
            doors[str(k)] = Door(str(k), seg, rs)
        obstacles = tuple(_rect(v, f"obstacle {i}") for i, v in enumerate(d["obstacles"]))
        ch = d["charger"]
        box = _rect(ch["box"], "charger box")
        light = tuple(float(c) for c in ch.get("light", ((box[0] + box[2]) / 2, (box[1] + box[3]) / 2)))
        ap = np.asarray(ch.get("approach", (1.0, 1.0)), dtype=float)
        if ap.shape != (2,) or not np.linalg.norm(ap) > 0:
            raise ValueError(f"charger approach must be a non-zero [dx, dy], got {ch.get('approach')!r}")
        if abs(np.linalg.norm(ap) - 1.0) > 1e-12:  # normalise once (keeps to_dict/from_dict exact)
            ap = ap / np.linalg.norm(ap)
        return cls(
            name=str(d["name"]),
            size=(float(d["size"][0]), float(d["size"][1])),
            rooms=rooms,
            walls=tuple(walls),
            doors=doors,
            obstacles=obstacles,
            charger=box,
            light=(light[0], light[1]),
            charger_approach=(float(ap[0]), float(ap[1])),
            locations={k: tuple(float(c) for c in v) for k, v in d.get("locations", {}).items()},
            subgoals={k: (float(v[0]), float(v[1])) for k, v in d.get("subgoals", {}).items()},
            description=str(d.get("description", "")),
        )

    @classmethod
    def from_json(cls, path) -> Layout:
        with open(path) as f:
            return cls.from_dict(json.load(f))

    @classmethod
    def load(cls, name: str) -> Layout:
        """A shipped layout by name (``default`` or ``changed``) or a path to a JSON file."""
        p = Path(name)
        if p.suffix == ".json" and p.exists():
            return cls.from_json(p)
        base = LAYOUT_DIR
        f = base / f"{name}.json"
        if not f.is_file():
            known = sorted(x.name[:-5] for x in base.iterdir() if x.name.endswith(".json"))
            raise ValueError(f"unknown layout {name!r}; shipped layouts are {known} (or pass a .json path)")
        return cls.from_dict(json.loads(f.read_text()))

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "description": self.description,
            "size": list(self.size),
            "rooms": {k: list(v) for k, v in self.rooms.items()},
            "walls": [list(w) for w in self.walls],
            "doors": {k: {"segment": list(d.segment), "rooms": list(d.rooms)} for k, d in self.doors.items()},
            "obstacles": [list(o) for o in self.obstacles],
            "charger": {"box": list(self.charger), "light": list(self.light),
                        "approach": list(self.charger_approach)},
            "locations": {k: list(v) for k, v in self.locations.items()},
            "subgoals": {k: list(v) for k, v in self.subgoals.items()},
        }

    def with_door_width(self, width: float) -> Layout:
        """A copy whose doorways are ``width`` in wide, each about its own centre, the abutting collinear
        wall segments cut back or extended to meet the new jambs (a sensitivity study of SPEC 5's 36 in).
        Layouts with a wall meeting a jamb at an angle (a door return) are refused rather than guessed."""
        if not (math.isfinite(width) and width > 2 * ROBOT_RADIUS):
            raise ValueError(f"door width must be a finite number of inches above the robot's diameter "
                             f"({2 * ROBOT_RADIUS:g}), got {width!r}")
        d = self.to_dict()
        walls = [list(w) for w in d["walls"]]
        for name, door in self.doors.items():
            u = (np.asarray(door.segment[2:]) - door.segment[:2]) / door.width
            old = (np.asarray(door.segment[:2]), np.asarray(door.segment[2:]))
            new = (door.center - u * width / 2, door.center + u * width / 2)
            for o, n in zip(old, new, strict=True):
                for w, end in [(w, e) for w in walls for e in (0, 2) if np.allclose(w[e:e + 2], o)]:
                    other = np.asarray(w[2 - end:4 - end])
                    v = other - o
                    if abs(float(u[0] * v[1] - u[1] * v[0])) > 1e-9:
                        raise ValueError(f"door {name!r}: wall {tuple(w)} meets a jamb at an angle; "
                                         "with_door_width only moves walls in line with the door")
                    if np.dot(other - n, o - door.center) <= 0:
                        raise ValueError(f"door {name!r} {width:g} in wide would swallow a whole wall")
                    w[end:end + 2] = [float(n[0]), float(n[1])]
            d["doors"][name]["segment"] = [float(v) for v in (*new[0], *new[1])]
        d["walls"] = walls
        d["name"] = f"{self.name}-door{width:g}"
        d["description"] = f"{self.description} Doorways {width:g} in wide."
        return Layout.from_dict(d)

    # -- derived geometry ---------------------------------------------------------------------------
    @property
    def segments(self) -> np.ndarray:
        """All solid segments, shape (N, 4): walls, then obstacle edges, then charger edges."""
        return self._geometry()[0]

    @property
    def kinds(self) -> np.ndarray:
        """Kind of each segment in :attr:`segments` (SEG_WALL, SEG_OBSTACLE, SEG_CHARGER)."""
        return self._geometry()[1]

    def _geometry(self):
        cache = self.__dict__.get("_geom")
        if cache is None:
            segs, kinds = [], []
            for w in self.walls:
                segs.append(w)
                kinds.append(SEG_WALL)
            for o in self.obstacles:
                segs += _rect_segments(o)
                kinds += [SEG_OBSTACLE] * 4
            segs += _rect_segments(self.charger)
            kinds += [SEG_CHARGER] * 4
            cache = (np.ascontiguousarray(segs, dtype=np.float64), np.asarray(kinds, dtype=np.int64))
            object.__setattr__(self, "_geom", cache)
        return cache

    def room_at(self, x: float, y: float) -> str | None:
        """Name of the room whose rectangle holds (x, y); on a shared boundary the first listed wins."""
        for name, (x0, y0, x1, y1) in self.rooms.items():
            if x0 <= x < x1 and y0 <= y < y1:
                return name
        return None

    def clearance(self, x: float, y: float) -> float:
        """Distance from (x, y) to the nearest solid segment."""
        return float(_point_segments_distance(x, y, self.segments))

    def is_free(self, x: float, y: float, margin: float = 1.0) -> bool:
        """True when a robot centred at (x, y) is inside a room and at least ``margin`` from any surface."""
        return self.room_at(x, y) is not None and self.clearance(x, y) >= ROBOT_RADIUS + margin

    def light_visible(self, x: float, y: float) -> bool:
        """Line of sight from (x, y) to the light within LIGHT_RANGE (the charger box does not block)."""
        lx, ly = self.light
        if math.hypot(lx - x, ly - y) > LIGHT_RANGE:
            return False
        return not _segment_blocked(x, y, lx, ly, self.segments, self.kinds)


# ---------------------------------------------------------------------------------------------------
# Numba kernels (all rays vs all segments in compiled loops; ~1-3 us per call)
@nb.njit(cache=True)
def _point_segments_distance(px, py, segs):
    best = np.inf
    for i in range(segs.shape[0]):
        ax, ay, bx, by = segs[i, 0], segs[i, 1], segs[i, 2], segs[i, 3]
        ex, ey = bx - ax, by - ay
        ll = ex * ex + ey * ey
        s = 0.0 if ll == 0.0 else ((px - ax) * ex + (py - ay) * ey) / ll
        s = min(1.0, max(0.0, s))
        dx, dy = ax + s * ex - px, ay + s * ey - py
        d = math.sqrt(dx * dx + dy * dy)
        if d < best:
            best = d
    return best


@nb.njit(cache=True)
def _segment_blocked(x0, y0, x1, y1, segs, kinds):
    """Does the open segment (x0,y0)-(x1,y1) cross a non-charger segment?"""
    dx, dy = x1 - x0, y1 - y0
    for i in range(segs.shape[0]):
        if kinds[i] == SEG_CHARGER:
            continue
        ax, ay = segs[i, 0], segs[i, 1]
        ex, ey = segs[i, 2] - ax, segs[i, 3] - ay
        den = dx * ey - dy * ex
        if den == 0.0:
            continue
        wx, wy = ax - x0, ay - y0
        t = (wx * ey - wy * ex) / den
        s = (wx * dy - wy * dx) / den
        if 0.0 < t < 1.0 and 0.0 <= s <= 1.0:
            return True
    return False


@nb.njit(cache=True)
def _cast_rays(x, y, heading_deg, segs, out):
    """Centre-to-surface distance along each of the 24 rays (inf when nothing is hit)."""
    for k in range(out.shape[0]):
        a = math.radians(heading_deg + RAY_STEP_DEG * k)
        dx, dy = math.cos(a), math.sin(a)
        best = np.inf
        for i in range(segs.shape[0]):
            ax, ay = segs[i, 0], segs[i, 1]
            ex, ey = segs[i, 2] - ax, segs[i, 3] - ay
            den = dx * ey - dy * ex
            if den == 0.0:
                continue
            wx, wy = ax - x, ay - y
            t = (wx * ey - wy * ex) / den
            if t <= 0.0 or t >= best:
                continue
            s = (wx * dy - wy * dx) / den
            if 0.0 <= s <= 1.0:
                best = t
        out[k] = best


@nb.njit(cache=True)
def _time_of_impact(x, y, dx, dy, segs, radius):
    """First contact of a disc moving from (x,y) by (dx,dy) with any segment.

    Returns (t, cx, cy, i): t in [0, 1] of first contact (t > 1: no contact), the contact point and
    the segment index.
    """
    best_t, bcx, bcy, bi = 2.0, 0.0, 0.0, -1
    a = dx * dx + dy * dy
    if a == 0.0:
        return best_t, bcx, bcy, bi
    r2 = radius * radius
    for i in range(segs.shape[0]):
        ax, ay, bx, by = segs[i, 0], segs[i, 1], segs[i, 2], segs[i, 3]
        # Endpoints: |p + t d - P| = r.
        for e in range(2):
            qx, qy = (ax, ay) if e == 0 else (bx, by)
            fx, fy = x - qx, y - qy
            b = 2.0 * (fx * dx + fy * dy)
            c = fx * fx + fy * fy - r2
            if c <= 0.0:
                t = 0.0 if b < 0.0 else 2.0  # already touching: only moving closer counts
            else:
                disc = b * b - 4.0 * a * c
                t = 2.0 if disc < 0.0 else (-b - math.sqrt(disc)) / (2.0 * a)
            if 0.0 <= t < best_t:
                best_t, bcx, bcy, bi = t, qx, qy, i
        # Interior: signed distance to the supporting line reaches +-r with the foot inside the segment.
        ex, ey = bx - ax, by - ay
        ln = math.sqrt(ex * ex + ey * ey)
        if ln == 0.0:
            continue
        ux, uy = ex / ln, ey / ln
        nx, ny = -uy, ux
        s0 = nx * (x - ax) + ny * (y - ay)
        sd = nx * dx + ny * dy
        side = 1.0 if s0 >= 0.0 else -1.0
        if side * sd >= 0.0:
            continue  # moving parallel to or away from the line
        t = (side * radius - s0) / sd
        if t < 0.0:
            t = 0.0 if abs(s0) <= radius else 2.0
        if t < best_t:
            cx = x + t * dx - side * radius * nx
            cy = y + t * dy - side * radius * ny
            proj = ux * (cx - ax) + uy * (cy - ay)
            if 0.0 <= proj <= ln:
                best_t, bcx, bcy, bi = t, cx, cy, i
    return best_t, bcx, bcy, bi


@nb.njit(cache=True)
def _scan(x, y, heading_deg, segs, kinds, lx, ly, radius, u, noise, true_out, sonar_out, light_out, door_out):
    """One sensor sweep: true body ranges, noisy sonar, light bits and door-edge bits."""
    n = true_out.shape[0]
    _cast_rays(x, y, heading_deg, segs, true_out)
    for k in range(n):
        r = true_out[k] - radius
        r = min(max(r, 0.0), 1e6)
        true_out[k] = min(r, float(SONAR_MAX))
        if noise:
            r = r * (1.0 - SONAR_ERROR + 2.0 * SONAR_ERROR * u[k])
        sonar_out[k] = min(float(SONAR_MAX), float(np.floor(r + 0.5)))
    if noise and u[n] < DROPOUT_PROB:
        sonar_out[min(int(u[n + 1] * n), n - 1)] = float(SONAR_MAX)
    # Light: one point source, thresholded direction bits.
    for k in range(n):
        light_out[k] = 0
    ddx, ddy = lx - x, ly - y
    if math.sqrt(ddx * ddx + ddy * ddy) <= LIGHT_RANGE and not _segment_blocked(x, y, lx, ly, segs, kinds):
        rel = math.degrees(math.atan2(ddy, ddx)) - heading_deg
        for k in range(n):
            diff = (rel - RAY_STEP_DEG * k + 180.0) % 360.0 - 180.0
            if abs(diff) <= LIGHT_HALF_ANGLE:
                light_out[k] = 1
    # Door edges: an abrupt jump between neighbours marks the nearer reading.
    for k in range(n):
        door_out[k] = 0
    for k in range(n):
        j = (k + 1) % n
        diff = sonar_out[k] - sonar_out[j]
        if diff >= DOOR_EDGE_JUMP:
            door_out[j] = 1
        elif -diff >= DOOR_EDGE_JUMP:
            door_out[k] = 1


# ---------------------------------------------------------------------------------------------------
# Simulator
class Motion(NamedTuple):
    """Outcome of one action."""

    action: int
    collided: bool  # the move was cancelled
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
    """

    def __init__(self, layout: Layout | str = "default", rng: np.random.Generator | None = None, *,
                 sensor_noise: bool = True, control_noise: bool = True):
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
        scale = 1.0 - CONTROL_ERROR + 2.0 * CONTROL_ERROR * u if self.control_noise else 1.0
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
              ROBOT_RADIUS, u, self.sensor_noise, ranges, sonar, light, door)
        return Reading(sonar, ranges, light, door, self.last_collision.copy(), self.heading, self.room)

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


# ---------------------------------------------------------------------------------------------------
# Rendering (matplotlib Agg, no pyplot state; works headless)
_ROOM_COLOURS = ("#f3efe4", "#e8eef3", "#eef3e8", "#f3e8ee")


def draw_layout(ax, layout: Layout, *, labels: bool = True, locations: bool = False) -> None:
    """Draw rooms, walls, doorways, obstacles, charger and light on a matplotlib Axes."""
    from matplotlib.patches import Circle, Rectangle

    for i, (name, (x0, y0, x1, y1)) in enumerate(layout.rooms.items()):
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor=_ROOM_COLOURS[i % 4], edgecolor="none"))
        if labels:
            ax.text(x1 - 8, y1 - 8, name, ha="right", va="top", fontsize=14, color="#777", weight="bold")
    for o in layout.obstacles:
        ax.add_patch(Rectangle((o[0], o[1]), o[2] - o[0], o[3] - o[1], facecolor="#8a8a8a", edgecolor="#444"))
    for w in layout.walls:
        ax.plot([w[0], w[2]], [w[1], w[3]], color="black", lw=3, solid_capstyle="projecting")
    for d in layout.doors.values():
        s = d.segment
        ax.plot([s[0], s[2]], [s[1], s[3]], color="#b07a2a", lw=1, ls=":")
    c = layout.charger
    ax.add_patch(Rectangle((c[0], c[1]), c[2] - c[0], c[3] - c[1], facecolor="#2d6cdf", edgecolor="#123"))
    ax.add_patch(Circle(layout.light, 4.5, facecolor="#ffd21f", edgecolor="#a80", zorder=5))
    if labels:
        ax.text(c[0] + 1, c[3] + 3, "charger", fontsize=7, color="#123", va="bottom")
    if locations:
        for name, loc in layout.locations.items():
            ax.plot(loc[0], loc[1], marker="x", color="#c0392b", ms=6)
            ax.text(loc[0] + 5, loc[1] - 12, name, fontsize=8, color="#c0392b")
    w, h = layout.size
    ax.set_xlim(-6, w + 6)
    ax.set_ylim(-6, h + 6)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def draw_robot(ax, pose, *, colour="#c0392b", reading: Reading | None = None, rays: bool = False) -> None:
    """Draw the robot disc and heading line, optionally its sonar rays (from a Reading) and light bits."""
    from matplotlib.patches import Circle

    x, y, hd = pose
    h = math.radians(hd)
    if rays and reading is not None:
        for k in range(N_RAYS):
            a = h + math.radians(RAY_STEP_DEG * k)
            r = ROBOT_RADIUS + float(reading.sonar[k])
            ca, sa = math.cos(a), math.sin(a)
            x0, y0 = x + ROBOT_RADIUS * ca, y + ROBOT_RADIUS * sa
            lit = reading.light[k]
            ax.plot([x0, x + r * ca], [y0, y + r * sa], color="#e0a800" if lit else "#5dade2",
                    lw=1.6 if lit else 0.7, zorder=3)
            if reading.door_edge[k]:
                ax.plot(x + r * ca, y + r * sa, "o", color="#8e44ad", ms=3, zorder=4)
    ax.add_patch(Circle((x, y), ROBOT_RADIUS, facecolor="white", edgecolor=colour, lw=1.5, zorder=6))
    ax.plot([x, x + ROBOT_RADIUS * math.cos(h)], [y, y + ROBOT_RADIUS * math.sin(h)], color=colour, lw=2,
            zorder=7)


def _figure(layout: Layout, dpi: int, scale: float, title: str | None):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    w, h = layout.size
    top = 0.35 if title else 0.0  # inches kept free for the title
    fig = Figure(figsize=(scale * w / 100 + 0.2, scale * h / 100 + 0.2 + top), dpi=dpi)
    FigureCanvasAgg(fig)
    frac = top / fig.get_figheight()
    ax = fig.add_axes((0.01, 0.01, 0.98, 0.98 - frac))
    if title:
        ax.set_title(title, fontsize=9)
    return fig, ax


def _to_rgb(fig) -> np.ndarray:
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()


def render_frame(layout: Layout, pose, *, reading: Reading | None = None, rays: bool = False,
                 trace: Sequence[Sequence[float]] | None = None, title: str | None = None,
                 locations: bool = False, dpi: int = 100, scale: float = 1.5) -> np.ndarray:
    """Top-down RGB image (H, W, 3) uint8 of the layout with the robot, its path so far and, with
    ``rays`` and a ``reading``, the sonar rays (blue; yellow where a light bit is on) and door-edge
    dots (purple)."""
    fig, ax = _figure(layout, dpi, scale, title)
    draw_layout(ax, layout, locations=locations)
    if trace is not None and len(trace) > 1:
        p = np.asarray(trace, dtype=float)
        ax.plot(p[:, 0], p[:, 1], color="#c0392b", lw=1, alpha=0.6)
    draw_robot(ax, pose, reading=reading, rays=rays)
    return _to_rgb(fig)


def render_figure_5_3(layout: Layout | str = "default", *, seed: int = 0, file=None, dpi: int = 100) -> np.ndarray:
    """Fig. 5.3's four panels: (a) the layout with L1..L4, (b) sonar at L3 facing north, (c) at L4 (they
    look alike: the hidden state of Ch. 8), (d) the light bits at L2 facing north. Readings are noisy, drawn
    with ``seed``; purple dots mark door-edge bits. Returns the RGB image; with ``file`` also writes a PNG."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    layout = layout if isinstance(layout, Layout) else Layout.load(layout)
    sim = RobotSim(layout, np.random.default_rng(seed))
    w, h = layout.size
    fig = Figure(figsize=(2 * (1.5 * w / 100 + 0.2), 2 * (1.5 * h / 100 + 0.5)), dpi=dpi)
    FigureCanvasAgg(fig)
    panels = [("(a) the robot's world, locations L1-L4", None, False),
              ("(b) sonar at L3 facing north (dots: door edges)", "L3", True),
              ("(c) sonar at L4 facing north", "L4", True),
              ("(d) light bits at L2 facing north (yellow rays)", "L2", True)]
    for i, (title, loc, rays) in enumerate(panels):
        ax = fig.add_subplot(2, 2, i + 1)
        draw_layout(ax, layout, locations=loc is None)
        ax.set_title(title, fontsize=9)
        if loc is not None:
            if loc not in layout.locations:
                raise ValueError(f"layout {layout.name!r} has no location {loc!r}; it has {sorted(layout.locations)}")
            sim.place(*layout.locations[loc])
            draw_robot(ax, sim.pose, reading=sim.sense(), rays=rays)
    fig.tight_layout()
    img = _to_rgb(fig)
    if file is not None:
        save_png(img, file)
    return img


def render_paths(layout: Layout, paths: Sequence[Sequence[Sequence[float]]], *,
                 labels: Sequence[str] | None = None, title: str | None = None, file=None,
                 robots: bool = True, dpi: int = 100, scale: float = 1.5,
                 locations: bool = False) -> np.ndarray:
    """Draw several trajectories (each a sequence of (x, y[, heading]) poses) on the layout.

    The start of each path is marked "S" (as in Fig. 5.7) and, with ``robots``, the robot disc is drawn
    at the first and last pose. Returns the RGB image; with ``file`` also writes it as PNG (atomically).
    """
    fig, ax = _figure(layout, dpi, scale, title)
    draw_layout(ax, layout, locations=locations)
    colours = ("#c0392b", "#2471a3", "#229954", "#7d3c98", "#d35400", "#17a589")
    for i, path in enumerate(paths):
        p = np.asarray(path, dtype=float)
        if p.ndim != 2 or p.shape[0] == 0 or p.shape[1] < 2:
            raise ValueError(f"path {i} must be a non-empty sequence of (x, y[, heading]) poses")
        col = colours[i % len(colours)]
        ax.plot(p[:, 0], p[:, 1], color=col, lw=1.5, marker=".", ms=3,
                label=None if labels is None else labels[i], zorder=8)
        ax.text(p[0, 0] - 16, p[0, 1] + 6, "S", fontsize=10, weight="bold", color=col, zorder=9)
        if robots and p.shape[1] >= 3:
            draw_robot(ax, p[0, :3], colour=col)
            draw_robot(ax, p[-1, :3], colour=col)
    if labels is not None:
        ax.legend(loc="upper left", fontsize=7, framealpha=0.9)
    img = _to_rgb(fig)
    if file is not None:
        save_png(img, file)
    return img


def save_png(image: np.ndarray, file) -> None:
    """Write an RGB uint8 image as PNG atomically."""
    import io

    from matplotlib.image import imsave

    buf = io.BytesIO()
    imsave(buf, np.asarray(image), format="png")
    atomic_write_bytes(file, buf.getvalue())


class HumanViewer:
    """A matplotlib window for render_mode="human"; silently inert (one warning) when headless."""

    def __init__(self):
        import matplotlib

        self._ok = matplotlib.get_backend().lower() not in ("agg", "pdf", "ps", "svg", "cairo", "template")
        self._fig = self._im = None
        if not self._ok:
            warnings.warn("render_mode='human' needs an interactive matplotlib backend; running headless, "
                          "frames are not shown (use render_mode='rgb_array')", stacklevel=3)

    def show(self, img: np.ndarray, fps: float) -> None:
        if not self._ok:
            return
        import matplotlib.pyplot as plt

        if self._fig is None:
            plt.ion()
            self._fig, ax = plt.subplots()
            ax.axis("off")
            self._im = ax.imshow(img)
        else:
            self._im.set_data(img)
        self._fig.canvas.draw_idle()
        plt.pause(1.0 / fps)

    def close(self) -> None:
        if self._fig is not None:
            import matplotlib.pyplot as plt

            plt.close(self._fig)
            self._fig = None
