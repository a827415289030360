"""The recurrent nets' hidden layers summed in vector lanes (issue 45) are the unit-by-unit sums they replaced, bit
for bit: each unit still adds its bias, inputs and context in that order, so only the speed may change.

``_forward_by_unit`` and ``_taken_by_unit`` below are the kernels' forward passes as they were (one chain of
additions per hidden unit: ``_hidden`` and ``_output``, which the one-step ``_forward_all`` still uses);
benchmarks/bench_speedups.py times the first against the new one.
"""

from __future__ import annotations

import numba
import numpy as np
import pytest

from connrl.nets.kernels import (
    _bptt,
    _bptt_backward,
    _forward_sequence,
    _hidden,
    _hidden_lanes,
    _output,
    _squash_output,
    _transposed,
)


@numba.njit
def _forward_by_unit(w1, w2, xs, actions, feedback, scale, ys, cs):
    """``_forward_sequence`` as it was (before issue 45's second round): every net's hidden units one after another
    (``_hidden``, one chain of additions per unit), then its output."""
    n_t = xs.shape[0]
    n_c = cs.shape[1]
    h_all = np.empty((w1.shape[0], w1.shape[1]))
    shared = w2.shape[0] == 1
    cs[0, :] = 0.0
    for t in range(n_t):
        a = actions[t]
        for b in range(w1.shape[0]):
            _hidden(w1, b, xs[t], cs[t], h_all[b])
            _output(w2, 0 if shared else b, h_all[b], ys[t, b])
            for k in range(ys.shape[2]):
                ys[t, b, k] *= scale
        for k in range(n_c):
            cs[t + 1, k] = feedback * h_all[a, k]


def _net(rng, n_a=4, n_h=12, n_in=14, n_c=8, n_o=1, shared=False):
    w1 = rng.uniform(-0.6, 0.6, (n_a, n_h, n_in + n_c + 1))
    w2 = rng.uniform(-0.6, 0.6, (1 if shared else n_a, n_o, n_h + 1))
    return w1, w2


@pytest.mark.parametrize("shape", [(4, 12, 14, 8, 1, False), (3, 5, 7, 5, 2, True), (1, 24, 20, 0, 1, False)])
def test_forward_in_lanes_is_the_unit_by_unit_forward_bit_for_bit(shape):
    rng = np.random.default_rng(sum(shape[:4]))
    w1, w2 = _net(rng, *shape)
    n_a, n_o = shape[0], shape[4]
    for n_t in (1, 7, 60):
        xs = rng.choice([-0.5, 0.5], (n_t, w1.shape[2] - shape[3] - 1)) + rng.normal(0, 0.1, (n_t, shape[2]))
        acts = rng.integers(0, n_a, n_t)
        ys, cs = np.empty((n_t, n_a, n_o)), np.empty((n_t + 1, shape[3]))
        ys0, cs0 = np.empty_like(ys), np.empty_like(cs)
        _forward_sequence(w1, w2, xs, acts, 1.5, 200.0, ys, cs)
        _forward_by_unit(w1, w2, xs, acts, 1.5, 200.0, ys0, cs0)
        assert ys.tobytes() == ys0.tobytes() and cs.tobytes() == cs0.tobytes()


@pytest.mark.parametrize("shape", [(4, 12, 14, 8, 1, False), (3, 5, 7, 5, 2, True), (1, 24, 20, 0, 1, False)])
def test_bptt_in_lanes_is_the_backward_pass_of_the_unit_by_unit_forward(shape):
    rng = np.random.default_rng(sum(shape[:4]) + 1)
    w1, w2 = _net(rng, *shape)
    n_a, n_in, n_o, n_t = shape[0], shape[2], shape[4], 25
    xs, acts = rng.normal(size=(n_t, n_in)), rng.integers(0, n_a, n_t)
    targets, weights = rng.uniform(-50, 50, (n_t, n_o)), rng.choice([0.0, 1.0], n_t)
    g1, g2 = np.zeros_like(w1), np.zeros_like(w2)
    loss = _bptt(w1, w2, xs, acts, targets, weights, 1.5, 0.9, 200.0, g1, g2)
    hs, os, cs = _taken_by_unit(w1, w2, xs, acts, 1.5)
    r1, r2 = np.zeros_like(w1), np.zeros_like(w2)
    ref = _bptt_backward(w1, w2, xs, acts, targets, weights, 1.5, 0.9, 200.0, r1, r2, hs, os, cs)
    assert loss == ref and g1.tobytes() == r1.tobytes() and g2.tobytes() == r2.tobytes()


def test_one_net_in_lanes_is_hidden_bit_for_bit():
    rng = np.random.default_rng(7)
    w1, w2 = _net(rng)
    wt = _transposed(w1)
    x, c = rng.normal(size=14), rng.uniform(-0.5, 0.5, 8)
    for a in range(4):
        ref, lanes = np.empty(12), np.empty(12)
        _hidden(w1, a, x, c, ref)
        _hidden_lanes(wt, a * 12, a * 12 + 12, x, c, lanes)
        _squash_output(w2, a, lanes, np.empty(1))  # squashes the sums in place on its way to the output
        assert ref.tobytes() == lanes.tobytes()


@numba.njit
def _taken_by_unit(w1, w2, xs, actions, feedback):
    """The taken nets' hidden layers, raw outputs and the contexts, unit by unit (``_bptt``'s forward as it was)."""
    n_t, n_h, n_c = xs.shape[0], w1.shape[1], w1.shape[2] - xs.shape[1] - 1
    hs, os, cs = np.empty((n_t, n_h)), np.empty((n_t, w2.shape[1])), np.zeros((n_t + 1, n_c))
    for t in range(n_t):
        a = actions[t]
        _hidden(w1, a, xs[t], cs[t], hs[t])
        _output(w2, 0 if w2.shape[0] == 1 else a, hs[t], os[t])
        for k in range(n_c):
            cs[t + 1, k] = feedback * hs[t, k]
    return hs, os, cs
