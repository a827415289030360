"""The rotated net's values kernel (4.2.4) sums in the lanes of the AVX-512 loop it replaced: everywhere the same order
written out one lane at a time, and bit for bit the old fastmath loop on the CPU the stored results were made on
(znver5; on another CPU LLVM may have chosen another vector width for that loop)."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from connrl.envs.survival import ACTION_ROTATION, ROTATION_PERMUTATIONS
from connrl.nets.kernels import _dot_in_lanes, _fma, _rotated_values

from .lanes import lanes_one_at_a_time, stored_results_cpu

PERMS = np.ascontiguousarray(ROTATION_PERMUTATIONS[list(ACTION_ROTATION)])


@numba.njit(cache=False, fastmath=True)
def _gathered_fastmath(w1, w2, x, perms, scale, q):  # the kernel as it was before issue 45
    n_h, n_in = w1.shape[1], w1.shape[2] - 1
    for a in range(perms.shape[0]):
        out = w2[0, n_h]
        for j in range(n_h):
            s = w1[0, j, n_in]
            for i in range(n_in):
                s += w1[0, j, i] * x[perms[a, i]]
            out += w2[0, j] * (1.0 / (1.0 + math.exp(-s)) - 0.5)
        q[a] = scale * (1.0 / (1.0 + math.exp(-out)) - 0.5)


@numba.njit(cache=False)
def _lanes_one_at_a_time(w, x, n, start):
    """The order of ``_dot_in_lanes``, lane by lane in scalars."""
    return lanes_one_at_a_time(w, x, n, start, 8)


@numba.njit(cache=False)
def _dot(w, x, n, start):  # an intrinsic runs inside compiled code only
    return _dot_in_lanes(w, 0, x, 0, n, start)


@pytest.mark.parametrize("n", [0, 1, 7, 8, 9, 31, 32, 33, 40, 63, 64, 100, 145])
def test_the_lanes_are_those_written_out_one_at_a_time(n):
    rng = np.random.default_rng(n)
    for _ in range(200):
        w, x = rng.normal(0, 3, n + 3), rng.choice([0.0, 1.0, -0.5, 0.3], n + 3)
        start = float(rng.normal())
        assert _dot(w, x, n, start) == _lanes_one_at_a_time(w, x, n, start)
    assert _dot(w, x, n, start) == pytest.approx(start + float(w[:n] @ x[:n]), rel=1e-12, abs=1e-12)


def test_the_values_are_the_gathered_fastmath_loops():
    rng = np.random.default_rng(0)
    n_in = PERMS.shape[1]
    exact = stored_results_cpu()  # that loop's order is LLVM's there; elsewhere it may sum otherwise
    for _ in range(2000):
        w1 = rng.uniform(-1, 1, (1, 30, n_in + 1)) * rng.choice([0.01, 1.0, 30.0])
        w2 = rng.uniform(-1, 1, (1, 31))
        x = rng.choice([0.0, 1.0, 0.5, -0.5], n_in)
        q, ref = np.empty(4), np.empty(4)
        _rotated_values(w1, w2, x, PERMS, 2.0, q, np.empty(n_in))
        _gathered_fastmath(w1, w2, x, PERMS, 2.0, ref)
        if exact:
            np.testing.assert_array_equal(q, ref)
        else:
            np.testing.assert_allclose(q, ref, rtol=1e-12, atol=1e-12)


@numba.njit(cache=False)
def _values_one_lane_at_a_time(w1, w2, x, perms, scale, q):
    n_h, n_in = w1.shape[1], w1.shape[2] - 1
    for a in range(perms.shape[0]):
        xr = x[perms[a]]
        out = w2[0, n_h]
        for j in range(n_h):
            s = _lanes_one_at_a_time(w1[0, j], xr, n_in, w1[0, j, n_in])
            out = _fma(w2[0, j], 1.0 / (1.0 + math.exp(-s)) - 0.5, out)
        q[a] = scale * (1.0 / (1.0 + math.exp(-out)) - 0.5)


def test_the_values_are_the_lane_order_on_every_cpu():
    rng = np.random.default_rng(1)
    n_in = PERMS.shape[1]
    for _ in range(300):
        w1, w2 = rng.uniform(-1, 1, (1, 30, n_in + 1)), rng.uniform(-1, 1, (1, 31))
        x = rng.choice([0.0, 1.0, 0.5, -0.5], n_in)
        q, ref = np.empty(4), np.empty(4)
        _rotated_values(w1, w2, x, PERMS, 2.0, q, np.empty(n_in))
        _values_one_lane_at_a_time(w1, w2, x, PERMS, 2.0, ref)
        np.testing.assert_array_equal(q, ref)
