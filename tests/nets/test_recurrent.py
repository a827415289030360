"""Recurrent OAON (thesis 7.4): forward vs a NumPy reference, BPTT vs finite differences, decay, reset."""

import numpy as np
import pytest

from connrl.nets.recurrent import RecurrentNetConfig, RecurrentOAON, gradients


def f(x):
    return 1.0 / (1.0 + np.exp(-x)) - 0.5


def reference_forward(w1, w2, xs, actions, feedback, scale):
    """Naive NumPy unrolling: all nets read the shared context; the taken action's net makes the next one."""
    n_c = w1.shape[2] - xs.shape[1] - 1
    c = np.zeros(n_c)
    ys, cs = [], [c]
    for x, a in zip(xs, actions, strict=True):
        u = np.concatenate([x, c, [1.0]])
        hs = [f(w1[b] @ u) for b in range(w1.shape[0])]
        ys.append([scale * f(w2[b if w2.shape[0] > 1 else 0] @ np.append(hs[b], 1.0))
                   for b in range(w1.shape[0])])
        c = feedback * hs[a][:n_c]
        cs.append(c)
    return np.array(ys), np.array(cs)


def reference_loss(w1, w2, xs, actions, targets, weights, feedback, scale):
    ys, _ = reference_forward(w1, w2, xs, actions, feedback, scale)
    taken = ys[np.arange(len(actions)), actions]
    return 0.5 * np.sum(weights[:, None] * ((taken - targets) / scale) ** 2)


def make(share_output=False, n_outputs=2, n_context=3, seed=0, **kw):
    cfg = RecurrentNetConfig(n_inputs=4, n_hidden=5, n_context=n_context, n_outputs=n_outputs,
                             value_range=1.5, init_range=0.8, share_output=share_output, **kw)
    return RecurrentOAON(cfg, n_nets=3, rng=np.random.default_rng(seed))


def sequence(net, n_t=7, seed=1):
    rng = np.random.default_rng(seed)
    xs = rng.choice([-0.5, 0.5], size=(n_t, net.config.n_inputs))
    actions = rng.integers(0, net.n_nets, n_t)
    targets = rng.uniform(-1.4, 1.4, (n_t, net.config.n_outputs))
    weights = rng.uniform(0.0, 1.0, n_t)
    return xs, actions, targets, weights


@pytest.mark.parametrize("share_output", [False, True])
def test_online_and_sequence_forward_match_numpy_reference(share_output):
    net = make(share_output)
    assert net.w2.shape == ((1 if share_output else 3), 2, 6) and net.w1.shape == (3, 5, 4 + 3 + 1)
    xs, actions, _, _ = sequence(net)
    ys_ref, cs_ref = reference_forward(net.w1, net.w2, xs, actions, 1.5, net.scale)
    ys, cs = net.forward_sequence(xs, actions)
    np.testing.assert_allclose(ys, ys_ref, rtol=0, atol=1e-13)
    np.testing.assert_allclose(cs, cs_ref, rtol=0, atol=1e-13)
    net.reset()
    for t, (x, a) in enumerate(zip(xs, actions, strict=True)):
        np.testing.assert_allclose(net.context, cs_ref[t], atol=1e-13)
        np.testing.assert_allclose(net.step(x, a), ys_ref[t], atol=1e-13)
    assert np.all(np.abs(ys) < 1.5)  # outputs span +-value_range


def test_q_net_values_then_advance():
    net = make(n_outputs=1)
    xs, actions, _, _ = sequence(net)
    ys_ref, _ = reference_forward(net.w1, net.w2, xs, actions, 1.5, net.scale)
    net.reset()
    for t, (x, a) in enumerate(zip(xs, actions, strict=True)):
        np.testing.assert_allclose(net.values(x), ys_ref[t, :, 0], atol=1e-13)
        net.advance(a)
    with pytest.raises(RuntimeError, match="advance"):
        net.advance(0)  # the context was already advanced past the last forward pass
    with pytest.raises(ValueError, match="n_outputs=1"):
        make(n_outputs=2).values(xs[0])


def test_reset_zeroes_context_and_training_starts_from_zero_context():
    net = make()
    xs, actions, targets, _ = sequence(net)
    net.reset()
    first = net.outputs(xs[0])
    for x, a in zip(xs, actions, strict=True):
        net.step(x, a)
    assert np.any(net.context != 0)
    assert not np.allclose(net.outputs(xs[0]), first)  # history matters
    net.reset()
    np.testing.assert_array_equal(net.context, 0.0)
    np.testing.assert_array_equal(net.outputs(xs[0]), first)
    # forward_sequence / gradients ignore the online context
    for x, a in zip(xs, actions, strict=True):
        net.step(x, a)
    ys, cs = net.forward_sequence(xs, actions)
    np.testing.assert_array_equal(cs[0], 0.0)
    np.testing.assert_array_equal(ys[0], first)


@pytest.mark.parametrize("share_output", [False, True])
def test_bptt_matches_central_finite_differences(share_output):
    net = make(share_output, seed=2)
    xs, actions, targets, weights = sequence(net, n_t=8, seed=3)
    loss, g1, g2 = gradients(net.w1, net.w2, xs, actions, targets, weights,
                             feedback=1.5, decay=1.0, value_range=1.5)
    assert loss == pytest.approx(reference_loss(net.w1, net.w2, xs, actions, targets, weights, 1.5, 3.0),
                                 rel=1e-12)
    eps = 1e-5
    for w, g in ((net.w1, g1), (net.w2, g2)):
        fd = np.zeros_like(w)
        for idx in np.ndindex(w.shape):
            old = w[idx]
            w[idx] = old + eps
            lp = gradients(net.w1, net.w2, xs, actions, targets, weights, feedback=1.5, decay=1.0,
                           value_range=1.5)[0]
            w[idx] = old - eps
            lm = gradients(net.w1, net.w2, xs, actions, targets, weights, feedback=1.5, decay=1.0,
                           value_range=1.5)[0]
            w[idx] = old
            fd[idx] = (lp - lm) / (2 * eps)
        rel = np.linalg.norm(g - fd) / np.linalg.norm(g + fd)
        assert rel <= 1e-6, rel
    # the context weights really receive gradient through time
    assert np.abs(g1[:, :, 4:7]).max() > 1e-4


def test_decay_scales_gradient_by_decay_per_context_link():
    net = make(n_outputs=1, seed=4)
    xs, _, targets, _ = sequence(net, n_t=3, seed=5)
    actions = np.array([0, 1, 2])  # net a is used only at step a
    weights = np.array([0.0, 0.0, 1.0])  # error only at the last step
    kw = dict(feedback=1.5, value_range=1.5)
    _, g1_full, g2_full = gradients(net.w1, net.w2, xs, actions, targets, weights, decay=1.0, **kw)
    _, g1_dec, g2_dec = gradients(net.w1, net.w2, xs, actions, targets, weights, decay=0.9, **kw)
    assert np.abs(g1_full[0]).max() > 0 and np.abs(g1_full[1]).max() > 0
    np.testing.assert_allclose(g1_dec[2], g1_full[2], rtol=1e-13)  # no context link crossed
    np.testing.assert_allclose(g1_dec[1], 0.9 * g1_full[1], rtol=1e-12)  # one link
    np.testing.assert_allclose(g1_dec[0], 0.81 * g1_full[0], rtol=1e-12)  # two links
    np.testing.assert_allclose(g2_dec, g2_full, rtol=1e-13)
    _, g1_zero, _ = gradients(net.w1, net.w2, xs, actions, targets, weights, decay=0.0, **kw)
    np.testing.assert_array_equal(g1_zero[:2], 0.0)  # decay 0 = back-propagation without BPTT


def test_train_sequence_is_momentum_sgd_on_the_bptt_gradient_and_learns():
    net = make(seed=6, lr=0.3, momentum=0.9)
    xs, actions, targets, weights = sequence(net, seed=7)
    w1, w2 = net.w1.copy(), net.w2.copy()
    loss0, g1, g2 = gradients(w1, w2, xs, actions, targets, weights, feedback=1.5, decay=0.9, value_range=1.5)
    assert net.train_sequence(xs, actions, targets, weights) == pytest.approx(loss0, rel=1e-12)
    np.testing.assert_allclose(net.w1, w1 - 0.3 * g1, atol=1e-14)
    np.testing.assert_allclose(net.w2, w2 - 0.3 * g2, atol=1e-14)
    _, h1, _ = gradients(net.w1, net.w2, xs, actions, targets, weights,
                         feedback=1.5, decay=0.9, value_range=1.5)
    w1b = net.w1.copy()
    net.train_sequence(xs, actions, targets, weights)
    np.testing.assert_allclose(net.w1, w1b + 0.9 * (-0.3 * g1) - 0.3 * h1, atol=1e-14)
    for _ in range(300):
        loss = net.train_sequence(xs, actions, targets, weights)
    assert loss < 0.1 * loss0


def test_learns_a_hidden_state_sequence_task():
    """Targets depend on the first input only (a hidden state): needs the context path to be learned."""
    cfg = RecurrentNetConfig(n_inputs=1, n_hidden=6, n_context=2, lr=0.1, momentum=0.9, decay=1.0)
    net = RecurrentOAON(cfg, n_nets=1, rng=np.random.default_rng(0))
    seqs = []
    for first in (-0.5, 0.5):
        xs = np.zeros((4, 1))
        xs[0, 0] = first
        seqs.append((xs, np.zeros(4, dtype=int), np.full(4, 0.8 * np.sign(first))))
    for _ in range(400):
        for xs, acts, tg in seqs:
            net.train_sequence(xs, acts, tg)
    for xs, acts, tg in seqs:
        ys, _ = net.forward_sequence(xs, acts)
        np.testing.assert_allclose(ys[:, 0, 0], tg, atol=0.15)


def test_state_dict_roundtrip_and_shared_update_keeps_one_output_layer():
    net = make(share_output=True, seed=8)
    other = make(share_output=True, seed=9)
    other.load_state_dict(net.state_dict())
    xs, actions, targets, _ = sequence(net)
    ys_other, _ = other.forward_sequence(xs, actions)
    np.testing.assert_array_equal(ys_other, net.forward_sequence(xs, actions)[0])
    with pytest.raises(ValueError, match="w2"):
        make(share_output=False).load_state_dict(net.state_dict())


def test_determinism_same_seed_same_weights_and_training():
    a, b = make(seed=11), make(seed=11)
    xs, actions, targets, weights = sequence(a)
    for net in (a, b):
        for _ in range(3):
            net.train_sequence(xs, actions, targets, weights)
    np.testing.assert_array_equal(a.w1, b.w1)
    np.testing.assert_array_equal(a.w2, b.w2)


def test_bad_inputs_are_rejected_with_clear_errors():
    with pytest.raises(ValueError, match="n_context"):
        RecurrentNetConfig(n_inputs=4, n_hidden=3, n_context=5)
    with pytest.raises(ValueError, match="decay"):
        RecurrentNetConfig(n_inputs=4, n_hidden=3, n_context=1, decay=1.5)
    net = make()
    xs, actions, targets, _ = sequence(net)
    with pytest.raises(ValueError, match="xs"):
        net.train_sequence(xs[:, :3], actions, targets)
    with pytest.raises(ValueError, match="actions"):
        net.train_sequence(xs, actions + 3, targets)
    with pytest.raises(ValueError, match="targets"):
        net.train_sequence(xs, actions, targets[:, :1])
    with pytest.raises(ValueError, match="weights"):
        net.train_sequence(xs, actions, targets, -np.ones(len(xs)))
    with pytest.raises(ValueError, match="x must"):
        net.outputs(np.zeros(5))
