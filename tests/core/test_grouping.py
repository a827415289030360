"""State grouping (6.6.4): groups of consecutive similar states, random centres, rewards and discounts gamma^k."""

import numpy as np
import pytest

from connrl.core.grouping import group_lesson, group_states
from connrl.core.lessons import Lesson


class _FixedRng:
    """uniform() gives mu; integers(lo, hi) gives the centre lo + offset (clipped to the group)."""

    def __init__(self, mu, offset=0):
        self.mu, self.offset = mu, offset

    def uniform(self, lo, hi):
        return self.mu

    def integers(self, lo, hi):
        return min(lo + self.offset, hi - 1)


def test_groups_are_runs_within_mu_of_their_first_state():
    x = np.array([[0.0], [0.4], [0.9], [1.0], [3.0], [3.2]])
    # mu = 1: 0.4 and 0.9 lie within 1 of 0, 1.0 does not; 3.2 is within 1 of 3.0
    assert group_states(x, (1.0, 1.0), _FixedRng(1.0)).tolist() == [0, 3, 4]
    assert group_states(x, (0.0, 0.0), _FixedRng(0.0)).tolist() == [0, 1, 2, 3, 4, 5]  # mu 0: no grouping
    with pytest.raises(ValueError, match="mu_range"):
        group_states(x, (2.0, 1.0), _FixedRng(1.0))


def test_grouped_lesson_rewards_and_discounts_by_hand():
    # 6 steps; states 0-2 similar, 3 alone, 4-5 similar; final state 6
    x = np.array([[0.0], [0.1], [0.2], [5.0], [9.0], [9.1], [20.0]])
    lesson = Lesson(x, np.array([2, 2, 2, 3, 0, 0]), np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]), terminated=True)
    w = np.arange(24, dtype=float).reshape(6, 4)
    allowed = np.arange(28).reshape(7, 4) % 3 == 0
    g = group_lesson(lesson, 0.5, (1.0, 1.0), _FixedRng(1.0, offset=1), weights=w, allowed=allowed)
    assert g.centres.tolist() == [1, 3, 5]  # the second member of each group (the only one of group 3)
    assert g.lesson.actions.tolist() == [2, 3, 0]
    np.testing.assert_array_equal(g.lesson.inputs, x[[1, 3, 5, 6]])
    # centre 1 -> 3: r1 + 0.5 r2; 3 -> 5: r3 + 0.5 r4; 5 -> final: r5
    np.testing.assert_allclose(g.lesson.rewards, [2.0 + 0.5 * 3.0, 4.0 + 0.5 * 5.0, 6.0])
    np.testing.assert_allclose(g.discounts, [0.25, 0.25, 0.5])
    np.testing.assert_array_equal(g.weights, w[[1, 3, 5]])
    np.testing.assert_array_equal(g.allowed, allowed[[1, 3, 5, 6]])
    assert g.lesson.terminated


def test_centres_vary_so_every_state_is_trained_on_in_time():
    x = np.zeros((11, 2))  # 10 identical states: one group
    lesson = Lesson(x, np.zeros(10, dtype=int), np.zeros(10), terminated=False, truncated=True)
    rng = np.random.default_rng(0)
    seen = {int(group_lesson(lesson, 0.9, (0.5, 2.5), rng).centres[0]) for _ in range(200)}
    assert seen == set(range(10))  # footnote 5: sometimes b, sometimes c, sometimes d


def test_a_group_ends_where_the_action_changes():
    x = np.zeros((6, 1))  # identical states: only the actions split them
    assert group_states(x, (1.0, 1.0), _FixedRng(1.0), np.array([0, 0, 1, 1, 1, 0])).tolist() == [0, 2, 5]
    lesson = Lesson(np.zeros((4, 1)), np.array([3, 3, 1]), np.zeros(3), terminated=False, truncated=True)
    g = group_lesson(lesson, 0.9, (1.0, 1.0), _FixedRng(1.0))
    assert g.lesson.actions.tolist() == [3, 1] and g.centres.tolist() == [0, 2]


@pytest.mark.parametrize("bad", [(1.0,), "ab", (2.0, 1.0), None])
def test_bad_mu_range_is_one_clear_error(bad):
    with pytest.raises(ValueError, match="mu_range must be"):
        group_states(np.zeros((2, 1)), bad, _FixedRng(1.0))
