"""Lessons, the lesson memory and recency sampling (3.5, 5.1, App. A.2).

Vocabulary (3.5, 5.1): an *experience* is ``(x_t, a_t, x_{t+1}, r_t)``; a *lesson* is the sequence of
experiences of one trial. A lesson stores the network inputs ``x_0 .. x_n`` (n+1 rows), the actions and
rewards, and how it ended: ``terminated`` (a failure or the goal: the last next-state has value 0) or
``truncated`` (a time limit: not a failure, so its last experience bootstraps from ``x_n``).
Lesson files (plain JSON) are in ``connrl.core.lesson_files``; replay in ``connrl.core.replay``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Lesson:
    """The experiences of one trial (3.5, 5.1). ``inputs`` has one more row than ``actions``."""

    inputs: np.ndarray  # (n+1, d) network inputs x_0 .. x_n
    actions: np.ndarray  # (n,) int
    rewards: np.ndarray  # (n,) float
    terminated: bool  # last next-state is terminal (failure or goal): its value is 0
    truncated: bool = False  # cut by a time limit: bootstrap from x_n
    taught: bool = False  # a teacher's lesson (3.7): replayed with policy threshold 0
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        self.inputs = np.asarray(self.inputs, dtype=np.float64)
        self.actions = np.asarray(self.actions, dtype=np.int64)
        self.rewards = np.asarray(self.rewards, dtype=np.float64)
        n = self.actions.shape[0]
        if self.inputs.ndim != 2 or self.inputs.shape[0] != n + 1:
            raise ValueError(f"a lesson of {n} experiences needs {n + 1} input rows, got {self.inputs.shape}")
        if self.rewards.shape != (n,):
            raise ValueError(f"rewards must have shape ({n},), got {self.rewards.shape}")

    def __len__(self) -> int:
        return int(self.actions.shape[0])

    @classmethod
    def from_steps(cls, steps, *, taught: bool = False, meta: dict | None = None) -> Lesson:
        """Build a lesson from ``(x, a, r, y, terminated, truncated)`` tuples of consecutive steps."""
        steps = list(steps)
        if not steps:
            raise ValueError("a lesson needs at least one experience")
        inputs = [s[0] for s in steps] + [steps[-1][3]]
        return cls(np.array(inputs), np.array([s[1] for s in steps]), np.array([s[2] for s in steps]),
                   terminated=bool(steps[-1][4]), truncated=bool(steps[-1][5]), taught=taught,
                   meta=dict(meta or {}))


class LessonRecorder:
    """Accumulates one trial's experiences into a Lesson."""

    def __init__(self):
        self.inputs: list[np.ndarray] = []
        self.actions: list[int] = []
        self.rewards: list[float] = []

    def add(self, x: np.ndarray, a: int, r: float, y: np.ndarray) -> None:
        if not self.inputs:
            self.inputs.append(np.array(x, dtype=np.float64))
        self.actions.append(int(a))
        self.rewards.append(float(r))
        self.inputs.append(np.array(y, dtype=np.float64))

    def __len__(self) -> int:
        return len(self.actions)

    def empty(self) -> bool:
        """Nothing recorded yet, not even a trial's first input."""
        return not self.actions and not self.inputs

    def discard(self) -> None:
        """Drop what was recorded, even a step half-added when a signal arrived (no lesson is built from it)."""
        self.__init__()

    def finish(self, terminated: bool, truncated: bool) -> Lesson | None:
        if not self.actions:
            return None
        lesson = Lesson(np.stack(self.inputs), np.array(self.actions), np.array(self.rewards),
                        terminated=terminated, truncated=truncated)
        self.__init__()
        return lesson


# ------------------------------------------------------------------------------------ App. A.2 sampling

def recency_index(n: int, r: float) -> int:
    """App. A.2: index (0 = oldest, n-1 = latest) of the lesson chosen by the uniform draw ``r`` in [0, 1).

    ``w = min(3, 1 + 0.02 n)``, ``k = floor(n log(1 + r (e^w - 1)) / w)``: recent lessons are favoured
    more strongly as the memory fills.
    """
    if n < 1:
        raise ValueError("cannot choose a lesson from an empty memory")
    w = min(3.0, 1.0 + 0.02 * n)
    k = int(math.floor(n * math.log(1.0 + r * (math.exp(w) - 1.0)) / w))
    return min(k, n - 1)


class LessonMemory:
    """The latest ``capacity`` experienced lessons (100 in Ch. 4, 70 in Ch. 7), oldest first."""

    def __init__(self, capacity: int):
        if capacity < 1:
            raise ValueError(f"lesson memory capacity must be >= 1, got {capacity}")
        self.capacity = capacity
        self.lessons: list[Lesson] = []

    def add(self, lesson: Lesson) -> None:
        self.lessons.append(lesson)
        if len(self.lessons) > self.capacity:
            self.lessons.pop(0)

    def __len__(self) -> int:
        return len(self.lessons)

    def sample(self, rng: np.random.Generator) -> tuple[int, Lesson]:
        """One lesson chosen by App. A.2; returns (age, lesson) with age 0 for the latest."""
        k = recency_index(len(self.lessons), float(rng.random()))
        return len(self.lessons) - 1 - k, self.lessons[k]

    def sample_ages(self, rng: np.random.Generator, count: int) -> list[int]:
        """The ages of ``count`` lessons chosen as ``sample`` chooses them, from the same draws taken at once
        (``rng.random(count)`` is ``count`` calls of ``rng.random()``): a trial replays up to 1000 (issue 45)."""
        n = len(self.lessons)
        if count == 0:
            return []
        if n < 1:
            raise ValueError("cannot choose a lesson from an empty memory")
        w = min(3.0, 1.0 + 0.02 * n)
        spread = math.exp(w) - 1.0  # recency_index's arithmetic, in its order
        return [n - 1 - min(int(math.floor(n * math.log(1.0 + r * spread) / w)), n - 1)
                for r in rng.random(count).tolist()]


class MixedOptions(ValueError):
    """Some lessons of one packed call have per-step weights or allowed choices and some not (a behaviour-level
    trial begun without applicability, say): such lessons are replayed one by one."""


@dataclass(frozen=True)
class LessonPack:
    """Lessons laid end to end for one compiled call over many replays (issue 45): ``order[k]`` is the k-th replay's
    lesson among the distinct ones, whose steps are rows ``step_start[i]..step_start[i+1]`` of ``actions``,
    ``rewards`` and ``weights``, and whose n_i + 1 states start at row ``in_start[i]`` of ``inputs`` and
    ``allowed`` (0-row ``weights`` / ``allowed``: none)."""

    distinct: list[Lesson]
    order: np.ndarray  # (k,) int64
    inputs: np.ndarray  # (sum n_i + 1, d) float64
    actions: np.ndarray  # (sum n_i,) int64
    rewards: np.ndarray  # (sum n_i,) float64
    terminated: np.ndarray  # (distinct,) bool
    in_start: np.ndarray  # (distinct,) int64
    step_start: np.ndarray  # (distinct + 1,) int64
    weights: np.ndarray  # (sum n_i, A) float64 or (0, A)
    allowed: np.ndarray  # (sum n_i + 1, A) bool or (0, A)


def pack_lessons(lessons: list[Lesson], options, n_actions: int, check) -> LessonPack:
    """Pack ``lessons`` (the same lesson may come again), each distinct one with ``options(lesson)`` = its (weights,
    allowed) or (None, None), after ``check(lesson, weights, allowed)``, the refusals of a single replay."""
    slot: dict[int, int] = {}
    distinct: list[Lesson] = []
    order = np.empty(len(lessons), dtype=np.int64)
    for k, lesson in enumerate(lessons):
        i = slot.get(id(lesson))
        if i is None:
            i = slot[id(lesson)] = len(distinct)
            distinct.append(lesson)
        order[k] = i
    opts = [options(lesson) for lesson in distinct]
    for lesson, (w, m) in zip(distinct, opts, strict=True):
        check(lesson, w, m)
    has_w, has_m = (opts[0][0] is not None, opts[0][1] is not None) if opts else (False, False)
    if any((w is not None) != has_w or (m is not None) != has_m for w, m in opts):
        raise MixedOptions("the lessons of one call must all have per-step weights / allowed choices, or none")
    step_start = np.zeros(len(distinct) + 1, dtype=np.int64)
    np.cumsum([len(lesson) for lesson in distinct], out=step_start[1:])

    def joined(arrays, dtype, width):
        return np.concatenate(arrays).astype(dtype, copy=False) if arrays else np.zeros((0, width), dtype)

    return LessonPack(
        distinct, order, joined([x.inputs for x in distinct], np.float64, 0),
        joined([x.actions for x in distinct], np.int64, 0).reshape(-1),
        joined([x.rewards for x in distinct], np.float64, 0).reshape(-1),
        np.array([bool(x.terminated) for x in distinct], dtype=np.bool_),
        step_start[:-1] + np.arange(len(distinct)), step_start,
        joined([o[0] for o in opts] if has_w else [], np.float64, n_actions),
        joined([o[1] for o in opts] if has_m else [], np.bool_, n_actions))
