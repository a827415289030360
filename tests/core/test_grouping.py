"""State grouping (6.6.4): groups of consecutive similar states, random centres, rewards and discounts gamma^k."""

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from connrl.core.grouping import _pairwise_sum, _sq_distance, group_lesson, group_states, group_states_reference
from connrl.core.lessons import Lesson


class _FixedRng:
    """uniform() gives mu; integers(lo, hi) gives the centre lo + offset (clipped to the group)."""

    def __init__(self, mu, offset=0):
        self.mu, self.offset = mu, offset

    def uniform(self, lo, hi):
        return self.mu

    def integers(self, lo, hi):
        return min(lo + self.offset, hi - 1)


# the plain loop (a stand-in generator) and the compiled one (a Generator: low == high draws exactly that mu)
RNGS = [pytest.param(_FixedRng, id="plain"), pytest.param(lambda mu: np.random.default_rng(0), id="compiled")]


@pytest.mark.parametrize("make_rng", RNGS)
def test_groups_are_runs_within_mu_of_their_first_state(make_rng):
    x = np.array([[0.0], [0.4], [0.9], [1.0], [3.0], [3.2]])
    # mu = 1: 0.4 and 0.9 lie within 1 of 0, 1.0 does not (the distance must be below mu); 3.2 is within 1 of 3.0
    assert group_states(x, (1.0, 1.0), make_rng(1.0)).tolist() == [0, 3, 4]
    assert group_states(x, (0.0, 0.0), make_rng(0.0)).tolist() == [0, 1, 2, 3, 4, 5]  # mu 0: no grouping
    with pytest.raises(ValueError, match="mu_range"):
        group_states(x, (2.0, 1.0), make_rng(1.0))
    with pytest.raises(ValueError, match="finite"):
        group_states(x, (0.0, np.inf), make_rng(1.0))


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


@pytest.mark.parametrize("make_rng", RNGS)
def test_a_group_ends_where_the_action_changes(make_rng):
    x = np.zeros((6, 1))  # identical states: only the actions split them
    assert group_states(x, (1.0, 1.0), make_rng(1.0), np.array([0, 0, 1, 1, 1, 0])).tolist() == [0, 2, 5]
    with pytest.raises(IndexError):  # an action per state, as the plain loop reads them
        group_states(x, (1.0, 1.0), make_rng(1.0), np.array([0, 0, 1]))
    lesson = Lesson(np.zeros((4, 1)), np.array([3, 3, 1]), np.zeros(3), terminated=False, truncated=True)
    g = group_lesson(lesson, 0.9, (1.0, 1.0), _FixedRng(1.0))
    assert g.lesson.actions.tolist() == [3, 1] and g.centres.tolist() == [0, 2]


@pytest.mark.parametrize("bad", [(1.0,), "ab", (2.0, 1.0), None])
def test_bad_mu_range_is_one_clear_error(bad):
    with pytest.raises(ValueError, match="mu_range must be"):
        group_states(np.zeros((2, 1)), bad, _FixedRng(1.0))


def _old_group_lesson(lesson, gamma, mu_range, rng):
    """group_lesson as it was written before it was compiled (centres drawn per group, rewards by NumPy)."""
    n = len(lesson)
    starts = group_states_reference(lesson.inputs[:n], mu_range, rng, lesson.actions)
    ends = np.append(starts[1:], n)
    centres = np.array([int(rng.integers(s, e)) for s, e in zip(starts, ends, strict=True)], dtype=np.int64)
    nxt = np.append(centres[1:], n)
    rewards = np.array([np.sum(lesson.rewards[c:m] * gamma ** np.arange(m - c)) for c, m in zip(centres, nxt,
                                                                                                  strict=True)])
    return centres, rewards, gamma ** (nxt - centres).astype(np.float64)


@pytest.mark.parametrize("dim", [1, 3, 16, 17, 40])
def test_compiled_grouping_is_the_plain_loop_bit_for_bit(dim):
    data = np.random.default_rng(dim)
    for trial in range(30):
        n = int(data.integers(1, 300))
        # a random walk, so runs of nearby states form groups of many sizes; actions in long stretches
        x = np.cumsum(data.normal(0, 0.3 / np.sqrt(dim), (n + 1, dim)), axis=0)
        acts = np.repeat(data.integers(0, 4, n), data.integers(1, 40, n))[:n]
        lesson = Lesson(x, acts, data.normal(size=n) * (data.random(n) < 0.3), terminated=bool(trial % 2))
        a, b = np.random.default_rng(trial), np.random.default_rng(trial)
        assert group_states(x[:n], (0.5, 2.5), a).tolist() == group_states_reference(x[:n], (0.5, 2.5), b).tolist()
        g = group_lesson(lesson, 0.9, (0.25, 1.25), a)
        centres, rewards, discounts = _old_group_lesson(lesson, 0.9, (0.25, 1.25), b)
        assert g.centres.tolist() == centres.tolist()
        assert g.lesson.rewards.tobytes() == rewards.tobytes() and g.discounts.tobytes() == discounts.tobytes()
        assert a.random() == b.random()  # the same draws, in the same order


def test_compiled_distance_is_numpys_to_the_last_bits_and_sums_are_numpys_bit_for_bit():
    data = np.random.default_rng(0)
    d, acc = np.empty(40), np.empty(16)
    for dim in range(1, 41):
        x = data.normal(size=(2, dim)) * 10 ** data.uniform(-3, 3, (2, dim))
        assert _sq_distance(x, 0, 1, d[:dim], acc) == pytest.approx(np.linalg.norm(x[1] - x[0]) ** 2, rel=1e-14)
    for n in [0, 1, 7, 8, 9, 15, 16, 127, 128, 129, 255, 256, 257, 1000, 4099]:
        a = data.normal(size=n) * 10 ** data.uniform(-3, 3, n)
        assert 0.0 + _pairwise_sum(a, 0, n) == np.sum(a)


def _fma(a: float, b: float, c: float) -> float:
    return float(Fraction(a) * Fraction(b) + Fraction(c))  # exact, then rounded once (to nearest, as fma does)


def _haswell_sq_norm(v: np.ndarray) -> float:
    """|v|^2 in OpenBLAS's Haswell ddot order, by hand: 16 fma lanes over blocks of 16, its tree, a plain tail."""
    n1 = len(v) - len(v) % 16
    acc = [0.0] * 16
    for b in range(0, n1, 16):
        acc = [_fma(float(v[b + k]), float(v[b + k]), acc[k]) for k in range(16)]
    s = 0.0
    if n1:
        even = ((acc[0] + acc[2]) + (acc[4] + acc[6])) + ((acc[8] + acc[10]) + (acc[12] + acc[14]))
        odd = ((acc[1] + acc[3]) + (acc[5] + acc[7])) + ((acc[9] + acc[11]) + (acc[13] + acc[15]))
        s = even + odd
    for k in range(n1, len(v)):
        s += float(v[k]) * float(v[k])
    return s


def test_compiled_distance_sums_in_the_haswell_order_on_every_machine():
    data = np.random.default_rng(2)
    d, acc = np.empty(70), np.empty(16)
    for dim in list(range(1, 70)) * 3:
        x = data.normal(size=(2, dim)) * 10 ** data.uniform(-3, 3, (2, dim))
        assert _sq_distance(x, 0, 1, d[:dim], acc) == _haswell_sq_norm(x[1] - x[0])


def test_non_integer_actions_take_the_plain_loop():
    x = np.zeros((3, 1))  # identical states: only the actions split them; 0.5 and 1.0 differ, not cut to integers
    actions = np.array([0.0, 0.5, 1.0])
    assert group_states(x, (1.0, 1.0), np.random.default_rng(0), actions).tolist() == [0, 1, 2]


def test_compiled_distance_is_numpys_dot_bit_for_bit_where_the_results_were_made():
    if _blas_core() not in ("Haswell", "Zen"):  # the stored results' NumPy (OPENBLAS_CORETYPE=Haswell)
        pytest.skip(f"NumPy's dot sums in OpenBLAS's {_blas_core()} order here, not the Haswell order the stored "
                    "results were made in (set OPENBLAS_CORETYPE=Haswell)")
    data = np.random.default_rng(1)
    d, acc = np.empty(70), np.empty(16)
    for dim in list(range(1, 70)) * 20:
        x = data.normal(size=(2, dim)) * 10 ** data.uniform(-3, 3, (2, dim))
        diff = x[1] - x[0]
        assert _sq_distance(x, 0, 1, d[:dim], acc) == diff.dot(diff)


def _blas_core() -> str:
    import ctypes
    import glob

    for lib in glob.glob(str(Path(np.__file__).parents[1] / "numpy.libs" / "libscipy_openblas*")):
        f = getattr(ctypes.CDLL(lib), "scipy_openblas_get_corename64_", None)
        if f is not None:
            f.restype = ctypes.c_char_p
            return f().decode()
    return "unknown"
