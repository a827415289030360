"""A net whose one hidden layer every action's output reads (``NetConfig.shared_hidden``, 3.4's multi-output
alternative to OAON): its values against a forward pass written out in NumPy and its update against the independent
NumPy copy (tests/numpy_nets.py); its gradients against finite differences (test_mlp.py) and its compiled
whole-lesson replay (test_replay_kernels.py) are tested with OAON's."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.nets import OAON, NetConfig
from connrl.nets.mlp import symmetric_sigmoid
from tests.numpy_nets import NumpyOAON


def _net(seed=1, lr=0.05, momentum=0.9, value_range=3.0):
    cfg = NetConfig(6, 5, value_range=value_range, init_range=0.8, lr=lr, momentum=momentum, shared_hidden=True)
    return OAON(cfg, 4, np.random.default_rng(seed))


def test_one_hidden_layer_for_every_action():
    net = _net()
    assert net.w1.shape == (1, 5, 7) and net.w2.shape == (4, 6)
    x = np.random.default_rng(0).normal(size=6)
    h = symmetric_sigmoid(net.w1[0] @ np.append(x, 1.0))
    want = 6.0 * symmetric_sigmoid(net.w2 @ np.append(h, 1.0))  # scale 2 * value_range
    np.testing.assert_allclose(net.values(x), want, rtol=1e-12)
    for a in range(4):
        assert net.value(x, a) == pytest.approx(want[a], rel=1e-12)


def test_an_update_moves_the_shared_layer_and_only_its_own_output_row():
    net = _net(seed=3)
    ref = NumpyOAON(net)
    rng = np.random.default_rng(6)
    x_other = rng.normal(size=6)
    before = net.values(x_other)
    w1, w2 = net.w1.copy(), net.w2.copy()
    for a, target in ((1, 2.0), (3, -1.5), (1, 0.5)):
        x = rng.normal(size=6)
        assert net.update(x, a, target) == pytest.approx(ref.update(x, a, target), rel=1e-12)
    ref.assert_same(net)
    assert not np.array_equal(net.w1, w1)
    np.testing.assert_array_equal(np.flatnonzero(np.any(net.w2 != w2, axis=1)), [1, 3])
    # the interference 3.4 names: actions never updated change value through the shared layer
    assert np.all(net.values(x_other)[[0, 2]] != before[[0, 2]])


def test_shared_hidden_needs_a_hidden_layer():
    with pytest.raises(ValueError, match="shared_hidden needs a hidden layer"):
        NetConfig(4, 0, shared_hidden=True)
