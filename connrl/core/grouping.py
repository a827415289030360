"""State grouping (6.6.4): replay a long lesson as a shorter one whose steps stand for runs of similar states.

Consecutive states whose inputs lie within Euclidean distance mu of the run's first state, and at which the same
action (behaviour) was taken, form one group; mu is drawn uniformly from ``mu_range`` for each group (6.6.4: "a
random number between 0.5 and 2.5"). Each group is replayed as one state, its *centre*, a member drawn at random on
every replay so that every pattern is trained on in time (footnote 5). Between consecutive centres k steps apart,
the reward is the discounted sum of the k rewards and the discount is gamma^k (6.6.4: "the discount factor should be
changed to gamma^n"). Pure given the Generator.

Choices the thesis leaves open (docs/RECONSTRUCTION.md, "State grouping"): distances are measured to the group's
first state, not to every member; a group never spans a change of action (the thesis's example is the states "a
behavior takes the robot through"), so the centre's action is every member's and replay's test of bad choices,
made at the centre, speaks for the group; the final state (the lesson's last next state) is never grouped; steps of
the first group before its centre are not replayed (they lead to a state of the same group).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.core.lessons import Lesson


def check_mu_range(mu_range) -> tuple[float, float]:
    """``mu_range`` as (low, high) with 0 <= low <= high, else one clear ValueError."""
    try:
        lo, hi = (float(v) for v in mu_range)
    except (TypeError, ValueError):
        raise ValueError(f"mu_range must be two numbers (low, high), got {mu_range!r}") from None
    if not 0 <= lo <= hi:
        raise ValueError(f"mu_range must be (low, high) with 0 <= low <= high, got {mu_range!r}")
    return lo, hi


def group_states(inputs: np.ndarray, mu_range: tuple[float, float], rng: np.random.Generator,
                 actions: np.ndarray | None = None) -> np.ndarray:
    """Start index of each group of consecutive similar rows of ``inputs`` (see the module docstring); with
    ``actions``, a group also ends where the action changes."""
    x = np.asarray(inputs, dtype=np.float64)
    lo, hi = check_mu_range(mu_range)
    starts, i = [], 0
    while i < len(x):
        starts.append(i)
        mu = rng.uniform(lo, hi)
        j = i + 1
        while j < len(x) and np.linalg.norm(x[j] - x[i]) < mu and (actions is None or actions[j] == actions[i]):
            j += 1
        i = j
    return np.array(starts, dtype=np.int64)


@dataclass(frozen=True)
class GroupedLesson:
    """A lesson rewritten over group centres, with what ``connrl.core.replay.replay_q`` needs to replay it."""

    lesson: Lesson  # inputs: the centres, then the original final state; actions: those taken at the centres
    discounts: np.ndarray  # gamma^k per step, k = the steps from one centre to the next
    centres: np.ndarray  # index of each centre in the original lesson
    weights: np.ndarray | None = None  # the original per-step rows at the centres
    allowed: np.ndarray | None = None  # rows at the centres and the final state


def group_lesson(lesson: Lesson, gamma: float, mu_range: tuple[float, float], rng: np.random.Generator,
                 weights: np.ndarray | None = None, allowed: np.ndarray | None = None) -> GroupedLesson:
    """6.6.4: ``lesson`` replayed over its groups of similar states (module docstring). ``weights`` (n, A) and
    ``allowed`` (n+1, A) per-step rows are carried over to the centres."""
    n = len(lesson)
    if n == 0:
        raise ValueError("a lesson to group needs at least one step")
    starts = group_states(lesson.inputs[:n], mu_range, rng, lesson.actions)
    ends = np.append(starts[1:], n)
    centres = np.array([int(rng.integers(s, e)) for s, e in zip(starts, ends, strict=True)], dtype=np.int64)
    nxt = np.append(centres[1:], n)
    steps = nxt - centres
    rewards = np.array([np.sum(lesson.rewards[c:m] * gamma ** np.arange(m - c)) for c, m in zip(centres, nxt,
                                                                                                  strict=True)])
    out = Lesson(lesson.inputs[np.append(centres, n)], lesson.actions[centres], rewards, lesson.terminated,
                 lesson.truncated, lesson.taught, dict(lesson.meta))
    return GroupedLesson(out, gamma ** steps.astype(np.float64), centres,
                         None if weights is None else np.asarray(weights)[centres],
                         None if allowed is None else np.asarray(allowed)[np.append(centres, n)])
