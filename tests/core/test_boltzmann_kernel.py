"""The compiled Boltzmann choice is boltzmann_select's: the same action from the same draw, the same probabilities,
bit for bit, and NumPy's own exp (not libm's, which differs in the last bit)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from connrl.core.boltzmann_kernel import _boltzmann_choice, _numpy_exp, _weighted_choice, compiled_choice_fits
from connrl.core.exploration import boltzmann_select, weighted_boltzmann_probabilities

pytestmark = pytest.mark.skipif(not compiled_choice_fits(4), reason="NumPy's exp loop not found here")


def test_numpy_exp_is_np_exp_where_libm_differs():
    z = np.random.default_rng(0).uniform(-700.0, 0.0, 20_000)
    out = np.empty_like(z)
    _numpy_exp(z, out, np.zeros(5, np.int64))
    np.testing.assert_array_equal(out, np.exp(z))
    assert any(math.exp(v) != w for v, w in zip(z.tolist(), out.tolist(), strict=True))  # the test can fail


@pytest.mark.parametrize("n", [1, 2, 4, 7])
def test_the_choice_is_boltzmann_selects(n):
    data = np.random.default_rng(n)
    rng, ref = np.random.default_rng(9), np.random.default_rng(9)
    p, scratch = np.empty(n), np.zeros(5, np.int64)
    for i in range(3000):
        q = data.normal(0.0, 1.0, n) * 10.0 ** data.uniform(-3, 1)
        if i % 7 == 0:
            q[data.integers(n)] = q.max()  # ties
        t = 10.0 ** data.uniform(-3, 1)
        a = _boltzmann_choice(q, t, rng, p, scratch)
        want, want_p = boltzmann_select(q, t, ref)
        assert a == want
        np.testing.assert_array_equal(p, want_p)
    assert rng.bit_generator.state == ref.bit_generator.state


def test_nan_merits_choose_as_searchsorted_does():
    rng, ref = np.random.default_rng(1), np.random.default_rng(1)
    p = np.empty(4)
    for q in ([0.1, np.nan, 0.3, 0.2], [np.nan] * 4, [0.2, 0.1, 0.0, np.nan]):
        q = np.array(q)
        assert _boltzmann_choice(q, 0.05, rng, p, np.zeros(5, np.int64)) == boltzmann_select(q, 0.05, ref)[0]


def test_eight_or_more_actions_are_not_compiled():
    assert not compiled_choice_fits(8)  # NumPy sums 8 or more pairwise
    assert not compiled_choice_fits(0)


@pytest.mark.parametrize("n", [1, 2, 4, 7])
def test_the_weighted_choice_is_eq_6_6_drawn_by_generator_choice(n):
    """Eq. 6.6 as ``BehaviourChoice.choose`` draws it: ``weighted_boltzmann_probabilities``, then ``rng.choice``."""
    data = np.random.default_rng(60 + n)
    rng, ref = np.random.default_rng(9), np.random.default_rng(9)
    p, scratch = np.empty(n), np.zeros(5, np.int64)
    for i in range(3000):
        q = data.normal(0.0, 1.0, n) * 10.0 ** data.uniform(-1, 3)
        w = data.choice(np.array([0.0, 1.0, 100.0]), n)
        w[data.integers(n)] = 1.0
        if i % 5 == 0:
            q[w == 0] = 1e6  # an excluded choice far above the rest: its exp overflows, and must not count
        t = 10.0 ** data.uniform(-2, 2)
        b = _weighted_choice(q, w, t, rng, p, scratch)
        with np.errstate(over="ignore", invalid="ignore"):
            want_p = weighted_boltzmann_probabilities(q, w, t)
        assert b == ref.choice(n, p=want_p)
        np.testing.assert_array_equal(p, want_p)
    assert rng.bit_generator.state == ref.bit_generator.state


def test_a_nan_among_the_allowed_choices_is_refused_without_a_draw():
    rng, p = np.random.default_rng(1), np.empty(4)
    state = rng.bit_generator.state
    for q, w in (([0.1, np.nan, 0.3, 0.2], [1.0, 1.0, 0.0, 1.0]), ([np.nan] * 4, [1.0] * 4)):
        q, w = np.array(q), np.array(w)
        with pytest.raises(ValueError, match="Probabilities contain NaN"):
            np.random.default_rng(1).choice(4, p=weighted_boltzmann_probabilities(q, w, 0.5))
        assert _weighted_choice(q, w, 0.5, rng, p, np.zeros(5, np.int64)) == -1
    assert rng.bit_generator.state == state
    q = np.array([0.1, np.nan, 0.3, 0.2])  # a NaN ruled out by W = 0 is never looked at
    assert _weighted_choice(q, np.array([1.0, 0.0, 1.0, 1.0]), 0.5, rng, p, np.zeros(5, np.int64)) >= 0
