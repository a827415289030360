"""Copying taught lessons onto Q-nets by supervised learning: the information test of a reconstruction.

A taught lesson says "in state x the teacher did a". Replayed as in 3.7 it only teaches the value of a; copied
here it teaches the choice itself: net a is trained towards +``margin`` and every other action's net towards
-``margin`` on each taught state (one-vs-rest regression, the same back-propagation, learning rate and momentum
as the agent's own nets), until the greedy action is the taught one on every taught state or ``epochs`` run out.

The greedy policy of such a copy is a reference for what the lessons *alone* can give, not a strict bound: it is one
capped one-vs-rest regressor, and a reinforcement learner also learns from its own trials (docs/RECONSTRUCTION.md,
"Calibration of door passing").
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from connrl.core.lessons import Lesson


def lesson_pairs(lessons: Sequence[Lesson]) -> tuple[np.ndarray, np.ndarray]:
    """All (state, taught action) pairs of the lessons, in order."""
    if not lessons:
        raise ValueError("copying needs at least one lesson")
    return (np.concatenate([lesson.inputs[:-1] for lesson in lessons]),
            np.concatenate([lesson.actions for lesson in lessons]).astype(np.int64))


def agreement(nets, states: np.ndarray, actions: np.ndarray) -> float:
    """Share of states whose greedy action (first maximum) is the taught one."""
    return float(np.mean([int(np.argmax(nets.values(x))) == a for x, a in zip(states, actions, strict=True)]))


def copy_epoch(nets, states: np.ndarray, actions: np.ndarray, margin: float, rng: np.random.Generator) -> None:
    """One pass over the pairs in a random order; every action's net gets its target on every state."""
    for i in rng.permutation(len(states)):
        for a in range(nets.n_nets):
            nets.update(states[i], a, margin if a == actions[i] else -margin)
