"""Copying taught lessons onto Q-nets (the copy bound of issue 12): pairs, agreement, one epoch's targets, and a copy
that reaches full agreement."""

import numpy as np
import pytest

from connrl.agents.cloning import agreement, copy_epoch, lesson_pairs
from connrl.core.lessons import Lesson
from connrl.nets import OAON, NetConfig


class Recorder:
    """Stands in for OAON: values are the first three inputs; updates are recorded."""

    n_nets = 3

    def __init__(self):
        self.calls = []

    def values(self, x):
        return np.asarray(x[:3], dtype=float)

    def update(self, x, a, target):
        self.calls.append((tuple(x), a, target))


def test_lesson_pairs_take_every_state_but_the_last():
    a = Lesson(np.arange(9.0).reshape(3, 3), [2, 0], [0.0, 1.0], terminated=True)
    b = Lesson(np.arange(10.0, 16.0).reshape(2, 3), [1], [1.0], terminated=True)
    states, actions = lesson_pairs([a, b])
    np.testing.assert_array_equal(states, [[0, 1, 2], [3, 4, 5], [10, 11, 12]])
    assert actions.tolist() == [2, 0, 1]
    with pytest.raises(ValueError, match="at least one lesson"):
        lesson_pairs([])


def test_agreement_counts_greedy_matches():
    states = np.array([[0.0, 1.0, 0.5], [2.0, 1.0, 0.0], [0.0, 0.0, 3.0]])
    assert agreement(Recorder(), states, np.array([1, 0, 0])) == pytest.approx(2 / 3)


def test_one_epoch_gives_every_net_its_target_on_every_state_once():
    nets, states, actions = Recorder(), np.eye(3) * 7, np.array([2, 0, 1])
    copy_epoch(nets, states, actions, 50.0, np.random.default_rng(0))
    assert len(nets.calls) == 9
    for i, x in enumerate(states):
        mine = [(a, t) for s, a, t in nets.calls if s == tuple(x)]
        assert mine == [(a, 50.0 if a == actions[i] else -50.0) for a in range(3)]


def test_copy_reaches_full_agreement_on_separable_states():
    rng = np.random.default_rng(1)
    nets = OAON(NetConfig(6, 4, value_range=100.0, init_range=0.5, lr=0.05, momentum=0.9), 3, rng)
    states, actions = rng.uniform(-1, 1, (6, 6)), np.array([0, 1, 2, 0, 1, 2])
    for _ in range(300):
        if agreement(nets, states, actions) == 1.0:
            break
        copy_epoch(nets, states, actions, 50.0, rng)
    assert agreement(nets, states, actions) == 1.0
