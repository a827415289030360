"""The MLP kernels of issue 45 against the fastmath loops they replaced: the hidden sums in ``_dot_in_fours``'s lanes,
and the replay that reuses the policy test's forward pass.

Bit for bit the old loops on the CPU the stored results were made on (znver5); elsewhere LLVM may have planned those
loops otherwise, and the written-out order is checked instead."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from connrl.nets.kernels import (
    _dot_in_fours,
    _mlp_forward,
    _mlp_update,
    _replay_mlp,
    _replay_q_steps,
)

from .lanes import lanes_one_at_a_time, stored_results_cpu


@numba.njit(cache=False, fastmath=True)
def _fastmath_forward(w1, w2, a, x, h):  # _mlp_forward as it was before issue 45
    n_h, n_in1 = w1.shape[1], w1.shape[2]
    n_in = n_in1 - 1
    out = w2[a, n_h]
    for j in range(n_h):
        s = w1[a, j, n_in]
        for i in range(n_in):
            s += w1[a, j, i] * x[i]
        hj = 1.0 / (1.0 + math.exp(-s)) - 0.5
        h[j] = hj
        out += w2[a, j] * hj
    return 1.0 / (1.0 + math.exp(-out)) - 0.5


@numba.njit(cache=False, fastmath=True)
def _fastmath_update(w1, w2, d1, d2, a, x, h, target, is_error, scale, lr, momentum):  # as it was, too
    n_h, n_in1 = w1.shape[1], w1.shape[2]
    n_in = n_in1 - 1
    y = _fastmath_forward(w1, w2, a, x, h)
    err = target if is_error else target - scale * y
    delta = err / scale * (0.25 - y * y)
    for j in range(n_h):
        dh = delta * w2[a, j] * (0.25 - h[j] * h[j])
        step = lr * delta * h[j] + momentum * d2[a, j]
        d2[a, j] = step
        w2[a, j] += step
        if dh != 0.0 or momentum != 0.0:
            for i in range(n_in):
                s = lr * dh * x[i] + momentum * d1[a, j, i]
                d1[a, j, i] = s
                w1[a, j, i] += s
            s = lr * dh + momentum * d1[a, j, n_in]
            d1[a, j, n_in] = s
            w1[a, j, n_in] += s
    step = lr * delta + momentum * d2[a, n_h]
    d2[a, n_h] = step
    w2[a, n_h] += step
    return scale * y


@numba.njit(cache=False)
def _dot(w, wo, x, xo, n, start):  # an intrinsic runs inside compiled code only
    return _dot_in_fours(w, wo, x, xo, n, start)


@pytest.mark.parametrize("n", [0, 1, 3, 4, 5, 14, 31, 32, 33, 36, 63, 64, 101, 145])
def test_the_hidden_sums_are_the_lanes_written_out_one_at_a_time(n):
    rng = np.random.default_rng(n)
    for _ in range(200):
        w, x = rng.normal(0, 3, n + 8), rng.choice([0.0, 1.0, -0.5, 0.3, 0.7], n + 8)
        start, wo, xo = float(rng.normal()), int(rng.integers(0, 5)), int(rng.integers(0, 5))
        assert _dot(w, wo, x, xo, n, start) == lanes_one_at_a_time(w[wo:], x[xo:], n, start, 4)
    assert _dot(w, 0, x, 0, n, start) == pytest.approx(start + float(w[:n] @ x[:n]), rel=1e-12, abs=1e-12)


def _random_net(rng, n_nets, n_h, n_in):
    w1 = rng.normal(0, 1, (n_nets, n_h, n_in + 1)) * rng.choice([0.01, 0.5, 3.0])
    w2 = rng.normal(0, 1, (n_nets, n_h + 1))
    x = rng.normal(0, 1, n_in) * rng.choice([0.1, 1.0, 3.0])
    x[rng.random(n_in) < 0.3] = 0.0
    return w1, w2, x


@pytest.mark.parametrize("n_h,n_in", [(1, 1), (8, 14), (9, 33), (30, 101), (16, 145)])
def test_the_forward_pass_is_the_fastmath_loops(n_h, n_in):
    rng = np.random.default_rng(n_h * 1000 + n_in)
    exact = stored_results_cpu()  # that loop's order is LLVM's there; elsewhere it may sum otherwise
    for _ in range(300):
        w1, w2, x = _random_net(rng, 3, n_h, n_in)
        a = int(rng.integers(3))
        h, h_ref = np.empty(n_h), np.empty(n_h)
        y, y_ref = _mlp_forward(w1, w2, a, x, h), _fastmath_forward(w1, w2, a, x, h_ref)
        if exact:
            assert y == y_ref
            np.testing.assert_array_equal(h, h_ref)
        else:
            assert y == pytest.approx(y_ref, rel=1e-12, abs=1e-12)
            np.testing.assert_allclose(h, h_ref, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("n_h,n_in", [(8, 14), (30, 101)])
def test_the_update_is_the_fastmath_loops(n_h, n_in):
    rng = np.random.default_rng(n_in)
    exact = stored_results_cpu()  # that loop's order is LLVM's there; elsewhere it may sum otherwise
    for k in range(200):
        w1, w2, x = _random_net(rng, 3, n_h, n_in)
        d1, d2 = rng.normal(0, 0.01, w1.shape) * (k % 2), rng.normal(0, 0.01, w2.shape) * (k % 2)
        args = (int(rng.integers(3)), x, np.empty(n_h), float(rng.normal()), k % 3 == 0, 2.0, 0.3, 0.9 * (k % 2))
        got, ref = [z.copy() for z in (w1, w2, d1, d2)], [z.copy() for z in (w1, w2, d1, d2)]
        out, out_ref = _mlp_update(*got, *args), _fastmath_update(*ref, *args)
        for g, r in zip([out, *got], [out_ref, *ref], strict=True):
            if exact:
                np.testing.assert_array_equal(g, r)
            else:
                np.testing.assert_allclose(g, r, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("p_threshold", [0.0, 0.05])
@pytest.mark.parametrize("per_step", [False, True])
def test_the_replay_that_reuses_the_forward_pass_is_the_step_by_step_one(p_threshold, per_step):
    """On every CPU: the two loops call the same net kernels, so they agree to the bit."""
    rng = np.random.default_rng(int(p_threshold * 100) + per_step)
    for k in range(60):
        n, n_a, n_h, n_in = int(rng.integers(1, 30)), 4, 8, 14
        w1, w2, _ = _random_net(rng, n_a, n_h, n_in)
        d1, d2 = np.zeros_like(w1), np.zeros_like(w2)
        inputs = rng.normal(0, 1, (n + 1, n_in))
        actions, rewards = rng.integers(0, n_a, n), rng.normal(0, 1, n)
        discounts = np.full(n, 0.9)
        weights = rng.choice([0.0, 1.0, 2.0], (n, n_a)) if per_step else np.zeros((0, n_a))
        allowed = rng.random((n + 1, n_a)) < 0.7 if per_step else np.zeros((0, n_a), dtype=np.bool_)
        common = (inputs, actions, rewards, k % 2 == 0, discounts, 0.8, 0.1, p_threshold, 0.5, k % 3 == 0, 2.0, 0.3,
                  0.9)
        a_nets, b_nets = [z.copy() for z in (w1, w2, d1, d2)], [z.copy() for z in (w1, w2, d1, d2)]
        used_a = _replay_mlp(*a_nets, np.empty(n_h), np.empty(n_a), *common, weights, allowed)
        used_b = _replay_q_steps(*b_nets, np.empty(n_h), np.empty(n_a), *common, 0, False, weights, allowed)
        assert used_a == used_b
        for g, r in zip(a_nets, b_nets, strict=True):
            np.testing.assert_array_equal(g, r)
