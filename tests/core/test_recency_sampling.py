"""App. A.2's recency rule for small memories, below the cap of w = Min(3, 1 + 0.02 n) (which binds from n = 100):
w = 1 + 0.02 n, r uniform in [0, 1), k = n log(1 + r (e^w - 1)) / w taken down to an integer (0 = oldest).

So k is chosen when e^(w k / n) <= 1 + r (e^w - 1) < e^(w (k+1) / n), i.e. with probability
P(k) = (e^(w (k+1) / n) - e^(w k / n)) / (e^w - 1), written out here without the library."""

import math

import numpy as np
import pytest

from connrl.core.lessons import Lesson, LessonMemory, recency_index

SMALL = (1, 2, 5, 10)


def a2_probabilities(n):
    w = 1.0 + 0.02 * n  # below the cap for n < 100
    return [(math.exp(w * (k + 1) / n) - math.exp(w * k / n)) / (math.exp(w) - 1.0) for k in range(n)]


def a2_cut(n, k):
    """The draw r at which the chosen index passes from k - 1 to k."""
    w = 1.0 + 0.02 * n
    return (math.exp(w * k / n) - 1.0) / (math.exp(w) - 1.0)


@pytest.mark.parametrize("n", SMALL)
def test_recency_index_changes_exactly_at_the_a2_cuts(n):
    assert recency_index(n, 0.0) == 0 and recency_index(n, 1.0 - 1e-12) == n - 1
    for k in range(1, n):
        cut = a2_cut(n, k)
        assert recency_index(n, cut - 1e-9) == k - 1
        assert recency_index(n, cut + 1e-9) == k


class GridDraws:
    """Stands in for the generator: ``random()`` returns the midpoints of m equal cells of [0, 1), in order."""

    def __init__(self, m):
        self.m, self.i = m, 0

    def random(self):
        self.i += 1
        return (self.i - 0.5) / self.m


@pytest.mark.parametrize("n", SMALL)
def test_lesson_memory_samples_ages_with_the_a2_probabilities(n):
    mem = LessonMemory(capacity=100)
    for i in range(n):
        mem.add(Lesson([[float(i)], [float(i)]], [0], [0.0], terminated=True))
    m = 20000
    draws, counts = GridDraws(m), [0] * n
    for _ in range(m):
        age, lesson = mem.sample(draws)
        assert lesson.inputs[0, 0] == n - 1 - age  # age 0 is the latest lesson
        counts[age] += 1
    p = a2_probabilities(n)
    for age in range(n):
        # each cell's midpoint decides it, so a frequency is off by at most one cell per cut
        assert counts[age] / m == pytest.approx(p[n - 1 - age], abs=2.0 / m)
    if n > 1:
        assert counts[0] > counts[-1]  # the latest is the likeliest


@pytest.mark.parametrize("n", (1, 7, 100, 250))
def test_ages_drawn_at_once_are_samples_one_by_one(n):
    """``sample_ages`` (a trial's draws in one call, issue 45) gives ``sample``'s ages from the same stream, at and
    above the cap of w."""
    mem = LessonMemory(capacity=300)
    for i in range(n):
        mem.add(Lesson([[float(i)], [float(i)]], [0], [0.0], terminated=True))
    rng, ref = np.random.default_rng(n), np.random.default_rng(n)
    assert mem.sample_ages(rng, 0) == []
    for count in (1, 5, 1000):
        assert mem.sample_ages(rng, count) == [mem.sample(ref)[0] for _ in range(count)]
    assert rng.bit_generator.state == ref.bit_generator.state
    with pytest.raises(ValueError, match="empty memory"):
        LessonMemory(3).sample_ages(rng, 2)
    assert LessonMemory(3).sample_ages(rng, 0) == []  # no replay asked of an empty memory: no error, as sample's
