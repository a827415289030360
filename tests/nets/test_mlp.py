"""Networks: symmetric sigmoid, forward pass against NumPy, backprop against finite differences, momentum."""

import dataclasses

import numpy as np
import pytest

from connrl.nets import OAON, NetConfig, symmetric_sigmoid


def numpy_forward(net: OAON, x, a):
    xb = np.append(x, 1.0)
    if net.config.n_hidden == 0:
        return net.scale * symmetric_sigmoid(net.w2[a] @ xb)
    h = symmetric_sigmoid(net.w1[_hidden_row(net, a)] @ xb)
    return net.scale * symmetric_sigmoid(net.w2[a] @ np.append(h, 1.0))


def _hidden_row(net: OAON, a):
    """The hidden layer net a reads: its own, or with ``shared_hidden`` the one every action shares."""
    return 0 if net.config.shared_hidden else a


def test_symmetric_sigmoid_values():
    assert symmetric_sigmoid(0.0) == 0.0
    assert symmetric_sigmoid(np.log(3.0)) == pytest.approx(0.25)  # 1/(1+1/3) - 0.5
    assert symmetric_sigmoid(-50.0) == pytest.approx(-0.5)


@pytest.mark.parametrize("hidden", [0, 5])
def test_values_match_numpy(hidden):
    rng = np.random.default_rng(1)
    net = OAON(NetConfig(7, hidden, value_range=3.0, init_range=0.8), 4, rng)
    x = rng.normal(size=7)
    np.testing.assert_allclose(net.values(x), [numpy_forward(net, x, a) for a in range(4)], rtol=1e-12)
    assert net.value(x, 2) == pytest.approx(numpy_forward(net, x, 2), rel=1e-12)


@pytest.mark.parametrize("hidden, shared", [(0, False), (6, False), (6, True)])
def test_gradients_match_finite_differences(hidden, shared):
    """With ``shared_hidden`` the hidden-layer gradient is that of the one layer every action reads."""
    rng = np.random.default_rng(2)
    net = OAON(NetConfig(5, hidden, value_range=2.0, init_range=1.0, shared_hidden=shared), 3, rng)
    x, a, target = rng.normal(size=5), 1, 0.7

    def loss():
        return 0.5 * ((target - numpy_forward(net, x, a)) / net.scale) ** 2

    g1, g2 = net.loss_gradients(x, a, target)
    eps = 1e-6
    for w, g, row in ((net.w1, g1, _hidden_row(net, a)), (net.w2, g2, a)):
        for idx in np.ndindex(w[row].shape):
            full = (row, *idx)
            old = w[full]
            w[full] = old + eps
            up = loss()
            w[full] = old - eps
            down = loss()
            w[full] = old
            assert g[idx] == pytest.approx((up - down) / (2 * eps), rel=1e-5, abs=1e-10)


@pytest.mark.parametrize("hidden", [0, 6])
def test_update_is_sgd_with_momentum(hidden):
    rng = np.random.default_rng(3)
    cfg = NetConfig(5, hidden, value_range=2.0, init_range=1.0, lr=0.3, momentum=0.5)
    net = OAON(cfg, 2, rng)
    x1, x2 = rng.normal(size=5), rng.normal(size=5)
    w1, w2 = net.w1.copy(), net.w2.copy()
    g1a, g2a = net.loss_gradients(x1, 0, 0.5)
    before = net.update(x1, 0, 0.5)
    assert before == pytest.approx(numpy_forward_copy(w1, w2, net, x1, 0))
    np.testing.assert_allclose(net.w2[0], w2[0] - 0.3 * g2a, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(net.w1[0], w1[0] - 0.3 * g1a, rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(net.w2[1], w2[1])  # other action's net untouched (OAON)
    # the second step adds momentum 0.5 * previous step
    step2_prev = net.w2[0] - w2[0]
    w2_before = net.w2.copy()
    g1b, g2b = net.loss_gradients(x2, 0, -0.2)
    net.update(x2, 0, -0.2)
    np.testing.assert_allclose(net.w2[0], w2_before[0] - 0.3 * g2b + 0.5 * step2_prev, rtol=1e-9, atol=1e-12)


def numpy_forward_copy(w1, w2, net, x, a):
    saved = net.w1.copy(), net.w2.copy()
    net.w1[...], net.w2[...] = w1, w2
    out = numpy_forward(net, x, a)
    net.w1[...], net.w2[...] = saved
    return out


def test_update_error_moves_output_by_error_direction():
    net = OAON(NetConfig(3, 4, lr=0.5, momentum=0.0, init_range=0.5), 2, np.random.default_rng(0))
    x = np.array([0.5, -0.5, 0.5])
    before = net.value(x, 1)
    net.update_error(x, 1, 0.3)
    assert net.value(x, 1) > before


def test_learns_a_target():
    net = OAON(NetConfig(3, 4, lr=0.5, momentum=0.9, init_range=0.5), 1, np.random.default_rng(0))
    x = np.array([0.5, -0.5, 0.5])
    for _ in range(300):
        net.update(x, 0, 0.6)
    assert net.value(x, 0) == pytest.approx(0.6, abs=1e-3)


def test_same_seed_same_weights():
    a = OAON(NetConfig(4, 3), 2, np.random.default_rng(7))
    b = OAON(NetConfig(4, 3), 2, np.random.default_rng(7))
    np.testing.assert_array_equal(a.w1, b.w1)
    np.testing.assert_array_equal(a.w2, b.w2)


@pytest.mark.parametrize("kwargs, word", [({"lr": -0.1}, "learning rate"), ({"n_hidden": -1}, "n_hidden"),
                                          ({"momentum": 1.0}, "momentum"), ({"init_range": 0}, "init_range")])
def test_bad_config_is_rejected(kwargs, word):
    with pytest.raises(ValueError, match=word):
        NetConfig(4, **{"n_hidden": 3, **kwargs})


def test_state_dict_round_trip():
    a = OAON(NetConfig(4, 3), 2, np.random.default_rng(7))
    b = OAON(NetConfig(4, 3), 2, np.random.default_rng(8))
    b.load_state_dict(a.state_dict())
    x = np.ones(4)
    np.testing.assert_array_equal(a.values(x), b.values(x))
    with pytest.raises(ValueError, match="shape"):
        OAON(NetConfig(5, 3), 2, np.random.default_rng(0)).load_state_dict(a.state_dict())


def test_linear_perceptron_is_value_range_times_net_and_follows_the_delta_rule():
    rng = np.random.default_rng(4)
    cfg = NetConfig(5, 0, value_range=2.0, init_range=1.0, lr=0.1, momentum=0.0, linear_output=True)
    net = OAON(cfg, 3, rng)
    x = rng.normal(size=5)
    xb = np.append(x, 1.0)
    np.testing.assert_allclose(net.values(x), 2.0 * (net.w2 @ xb), rtol=1e-12)
    # finite differences of 0.5 ((target - Q) / value_range)^2
    target, a = 0.7, 1
    _, g2 = net.loss_gradients(x, a, target)
    eps = 1e-6
    for i in range(6):
        old = net.w2[a, i]
        net.w2[a, i] = old + eps
        up = 0.5 * ((target - net.value(x, a)) / 2.0) ** 2
        net.w2[a, i] = old - eps
        down = 0.5 * ((target - net.value(x, a)) / 2.0) ** 2
        net.w2[a, i] = old
        assert g2[i] == pytest.approx((up - down) / (2 * eps), rel=1e-6, abs=1e-10)
    # one update is w += lr * (target - Q) / value_range * x  (Widrow-Hoff)
    w_before, q_before = net.w2[a].copy(), net.value(x, a)
    assert net.update(x, a, target) == pytest.approx(q_before)
    np.testing.assert_allclose(net.w2[a], w_before + 0.1 * (target - q_before) / 2.0 * xb, rtol=1e-12)


def test_linear_output_needs_a_perceptron():
    with pytest.raises(ValueError, match="linear_output"):
        NetConfig(4, 3, linear_output=True)


def test_output_init_sets_only_the_output_weights_range_and_keeps_the_random_stream():
    from connrl.nets.recurrent import RecurrentNetConfig, RecurrentOAON

    for make, cfg in ((OAON, NetConfig(5, 3, init_range=0.3)), (RecurrentOAON, RecurrentNetConfig(5, 3, 2,
                                                                                                    init_range=0.3))):
        a_rng, b_rng, c_rng = (np.random.default_rng(7) for _ in range(3))
        a, b = make(cfg, 2, a_rng), make(dataclasses.replace(cfg, output_init=None), 2, b_rng)
        zero = make(dataclasses.replace(cfg, output_init=0.0), 2, c_rng)
        np.testing.assert_array_equal(a.w1, b.w1)
        np.testing.assert_array_equal(a.w2, b.w2)  # None = init_range, bit for bit
        np.testing.assert_array_equal(zero.w1, a.w1)  # the hidden weights are the same draws
        assert not zero.w2.any() and a.w2.any()
        assert a_rng.random() == c_rng.random()  # the same number of draws either way
    for bad in (-0.1, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="output_init must be None or a finite number >= 0"):
            NetConfig(5, 3, output_init=bad)
