"""The HEROINE world's constants (robot, sensors, actions) and its office layout (Fig. 5.3, plain JSON data).

See the package docstring and docs/RECONSTRUCTION.md, "HEROINE robot world".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from connrl.envs.robot.constants import LIGHT_RANGE, ROBOT_RADIUS, SEG_CHARGER, SEG_OBSTACLE, SEG_WALL
from connrl.envs.robot.geometry import _point_segments_distance, _segment_blocked
from connrl.storage import FileError, read_json

LAYOUT_DIR = Path(__file__).resolve().parent.parent.parent / "data" / "layouts"


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
        """A layout file; FileError (a ValueError, one line naming the file) when it is not a layout."""
        d = read_json(path, "layout file", max_bytes=2**20)
        if not isinstance(d, dict):
            raise FileError(path, f"is a JSON {type(d).__name__}; a layout file holds one object")
        try:
            layout = cls.from_dict(d)
        except (ValueError, TypeError, KeyError, IndexError, AttributeError) as exc:
            raise FileError(path, f"is not a valid layout ({type(exc).__name__}: {exc})") from None
        if not all(math.isfinite(v) and abs(v) < 1e6 for v in np.concatenate([
                np.ravel(layout.size), layout.segments.ravel(), np.ravel(layout.charger), np.ravel(layout.light)])):
            raise FileError(path, "holds a coordinate beyond +-1e6 cm; layouts are a few metres across")
        return layout

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
        return cls.from_json(f)

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
        wall segments cut back or extended to meet the new jambs (the SPEC's 36 in, or a calibration's candidates).
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


