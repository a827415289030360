"""Lessons, lesson memory, recency sampling (App. A.2) and backward TD(lambda) replay (Fig. 5.1).

Vocabulary (3.5, 5.1): an *experience* is ``(x_t, a_t, x_{t+1}, r_t)``; a *lesson* is the sequence of
experiences of one trial. A lesson stores the network inputs ``x_0 .. x_n`` (n+1 rows), the actions and
rewards, and how it ended: ``terminated`` (a failure or the goal: the last next-state has value 0) or
``truncated`` (a time limit: not a failure, so its last experience bootstraps from ``x_n``).

The returns are pure functions (``td_lambda_target``, ``lambda_returns``); the replay loops
(``replay_q``, ``replay_ahc``) apply them to networks in the order of Fig. 5.1: backward from t = n-1, with
lambda set to 0 at the last step and after a non-policy action, and non-policy experiences not replayed
(3.5.1). Incremental mode updates after each experience (the default, 5.1.2); batch mode computes every
target from the networks as they were before the lesson, then updates.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np

from connrl.exploration import boltzmann_probabilities
from connrl.nets.mlp import OAON, replay_lesson_q
from connrl.storage import atomic_write_text

LESSON_FORMAT = "connrl-lesson"
LESSON_VERSION = 1


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


# ------------------------------------------------------------------------------------- pure TD(lambda)

def td_lambda_target(r: float, u_next: float, e_next: float, gamma: float, lam: float) -> float:
    """Eq. 5.5 / Fig. 5.1 step 4: ``e'_t = r_t + gamma [(1 - lam) u_{t+1} + lam e'_{t+1}]``."""
    return r + gamma * ((1.0 - lam) * u_next + lam * e_next)


def lambda_returns(rewards, next_values, gamma: float, lam, clip: float | None = None) -> np.ndarray:
    """TD(lambda) returns of a lesson computed backward (Eq. 5.5), for fixed predictions.

    ``next_values[t]`` is ``u_{t+1}`` (0 after a terminal step). ``lam`` is a scalar or a per-step array
    (use 0 where the following action was not a policy action); lambda is always 0 at the last step.
    ``clip`` truncates targets from above (4.2.4: Q and V targets above 1 are set to 1).
    """
    rewards = np.asarray(rewards, dtype=np.float64)
    u = np.asarray(next_values, dtype=np.float64)
    lams = np.broadcast_to(np.asarray(lam, dtype=np.float64), rewards.shape)
    out = np.empty_like(rewards)
    e_next = 0.0
    for t in range(rewards.size - 1, -1, -1):
        lam_t = 0.0 if t == rewards.size - 1 else lams[t]
        e = td_lambda_target(rewards[t], u[t], e_next, gamma, lam_t)
        if clip is not None and e > clip:
            e = clip
        out[t] = e
        e_next = e
    return out


# ------------------------------------------------------------------------------------------ replay loops

class QFunction(Protocol):
    """What replay needs of a Q-function: all action values, and a step toward a target for one action."""

    n_actions: int

    def values(self, x: np.ndarray) -> np.ndarray: ...

    def update(self, x: np.ndarray, a: int, target: float) -> float: ...


@dataclass(frozen=True)
class ReplayParams:
    """How one lesson is replayed (Fig. 5.1, 3.5.1, 5.1.2)."""

    gamma: float  # discount factor (3.2)
    lam: float = 0.0  # recency factor lambda of TD(lambda) (5.1); Ch. 3-4 use 0
    temperature: float = 0.0  # T of the current policy, for the non-policy test (3.5.1)
    p_threshold: float = 0.0  # P_t: actions with P(a|x) below it are non-policy, not replayed (3.5.1)
    batch: bool = False  # batch mode: targets from the nets as before the lesson (5.1.2, 7.5)
    clip: float | None = None  # truncate targets above this value (4.2.4)


def _is_policy(merits: np.ndarray, a: int, params: ReplayParams) -> bool:
    if params.p_threshold <= 0:
        return True
    return bool(boltzmann_probabilities(merits, params.temperature)[a] >= params.p_threshold)


def replay_q(q: QFunction, lesson: Lesson, params: ReplayParams) -> int:
    """Fig. 5.1(a): replay a lesson backward into a Q-function; returns how many experiences were used."""
    x, acts, rews = lesson.inputs, lesson.actions, lesson.rewards
    n = len(lesson)
    if type(q) is OAON and not params.batch:  # the same loop, compiled (see benchmarks/bench_core.py)
        return replay_lesson_q(q, x, acts, rews, lesson.terminated, params.gamma, params.lam, params.temperature,
                               params.p_threshold, params.clip)
    if params.batch:
        vals = [q.values(x[t]) for t in range(n + 1)]
        policy = np.array([_is_policy(vals[t], int(acts[t]), params) for t in range(n)])
        u = np.array([vals[t + 1].max() for t in range(n)])
        if lesson.terminated:
            u[-1] = 0.0
        lams = np.where(np.append(policy[1:], False), params.lam, 0.0)
        targets = lambda_returns(rews, u, params.gamma, lams, params.clip)
        for t in range(n - 1, -1, -1):
            if policy[t]:
                q.update(x[t], int(acts[t]), targets[t])
        return int(policy.sum())

    used = 0
    e_next, next_policy = 0.0, False
    for t in range(n - 1, -1, -1):
        u = 0.0 if (t == n - 1 and lesson.terminated) else float(q.values(x[t + 1]).max())
        lam_t = params.lam if (t < n - 1 and next_policy) else 0.0
        e = td_lambda_target(rews[t], u, e_next, params.gamma, lam_t)
        if params.clip is not None and e > params.clip:
            e = params.clip
        a = int(acts[t])
        next_policy = _is_policy(q.values(x[t]), a, params)
        if next_policy:
            q.update(x[t], a, e)
            used += 1
        e_next = e
    return used


def replay_ahc(v_net, policy_net, lesson: Lesson, params: ReplayParams) -> int:
    """Fig. 5.1(b): replay a lesson backward into a V-net (one output) and a policy net (one per action).

    Non-policy actions are judged by the Boltzmann probabilities of the policy net's merits (3.5.1).
    """
    x, acts, rews = lesson.inputs, lesson.actions, lesson.rewards
    n = len(lesson)
    used = 0
    e_next, next_policy = 0.0, False
    for t in range(n - 1, -1, -1):
        u = 0.0 if (t == n - 1 and lesson.terminated) else float(v_net.value(x[t + 1], 0))
        lam_t = params.lam if (t < n - 1 and next_policy) else 0.0
        e = td_lambda_target(rews[t], u, e_next, params.gamma, lam_t)
        if params.clip is not None and e > params.clip:
            e = params.clip
        a = int(acts[t])
        next_policy = _is_policy(policy_net.values(x[t]), a, params)
        if next_policy:
            v_before = v_net.update(x[t], 0, e)
            policy_net.update_error(x[t], a, e - v_before)
            used += 1
        e_next = e
    return used


# ------------------------------------------------------------------------------------------ lesson files

class LessonFileError(ValueError):
    """A lesson file that cannot be used: malformed, wrong version, or made for another task."""


def save_lessons(path, lessons: list[Lesson], *, env_id: str, env_kwargs: dict | None = None,
                 source: str = "") -> None:
    """Write taught lessons as versioned JSON (plain data: loading never executes code), atomically."""
    doc = {
        "format": LESSON_FORMAT,
        "version": LESSON_VERSION,
        "env_id": env_id,
        "env_kwargs": env_kwargs or {},
        "source": source,
        "lessons": [
            {
                "inputs": lesson.inputs.tolist(),
                "actions": lesson.actions.tolist(),
                "rewards": lesson.rewards.tolist(),
                "terminated": lesson.terminated,
                "truncated": lesson.truncated,
                "taught": lesson.taught,
                "meta": lesson.meta,
            }
            for lesson in lessons
        ],
    }
    atomic_write_text(path, json.dumps(doc))


def load_lessons(path, *, env_id: str | None = None, input_dim: int | None = None,
                 n_actions: int | None = None) -> list[Lesson]:
    """Read a lesson file written by ``save_lessons``; any mismatch raises LessonFileError saying what."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise LessonFileError(f"{path}: no such lesson file") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise LessonFileError(f"{path}: not a JSON lesson file ({exc})") from None
    if not isinstance(doc, dict) or doc.get("format") != LESSON_FORMAT:
        raise LessonFileError(f"{path}: 'format' must be {LESSON_FORMAT!r}")
    if doc.get("version") != LESSON_VERSION:
        raise LessonFileError(f"{path}: lesson format version {doc.get('version')!r} is not supported "
                              f"(this connrl reads version {LESSON_VERSION})")
    if env_id is not None and doc.get("env_id") != env_id:
        raise LessonFileError(f"{path}: lessons were recorded on {doc.get('env_id')!r}, expected {env_id!r}")
    out = []
    for i, raw in enumerate(doc.get("lessons") or []):
        try:
            lesson = Lesson(np.array(raw["inputs"], dtype=np.float64), np.array(raw["actions"]),
                            np.array(raw["rewards"], dtype=np.float64), terminated=bool(raw["terminated"]),
                            truncated=bool(raw.get("truncated", False)), taught=bool(raw.get("taught", True)),
                            meta=dict(raw.get("meta", {})))
        except (KeyError, TypeError, ValueError) as exc:
            raise LessonFileError(f"{path}: lesson {i} is malformed: {exc}") from None
        if input_dim is not None and lesson.inputs.shape[1] != input_dim:
            raise LessonFileError(f"{path}: lesson {i} has {lesson.inputs.shape[1]} inputs, "
                                  f"the agent expects {input_dim}")
        if n_actions is not None and len(lesson) and not (0 <= lesson.actions.min()
                                                          and lesson.actions.max() < n_actions):
            raise LessonFileError(f"{path}: lesson {i} has actions outside 0..{n_actions - 1}")
        out.append(lesson)
    if not out:
        raise LessonFileError(f"{path}: the file holds no lessons")
    return out
