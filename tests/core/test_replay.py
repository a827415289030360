"""Fig. 5.1 replay: order, non-policy actions, batch mode, Fig. 5.1(b), the 5.4.3 repairs, and the
compiled OAON kernel against the plain Python loop."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.core import replay as replay_module
from connrl.core.exploration import boltzmann_probabilities
from connrl.core.lessons import Lesson
from connrl.core.replay import (
    REPAIRS,
    ReplayParams,
    batch_targets,
    is_policy_action,
    policy_mask,
    repair_step,
    replay_ahc,
    replay_q,
    replay_q_reference,
)
from connrl.core.replay_kernel import replay_oaon
from connrl.core.returns import lambda_returns
from connrl.nets import OAON, NetConfig


class TableQ:
    """A tabular Q-function with an exact update (lr 1) to check the order of Fig. 5.1."""

    def __init__(self, n_states, n_actions, init=0.0):
        self.n_actions = n_actions
        self.table = np.full((n_states, n_actions), init)
        self.updates = []

    def values(self, x):
        return self.table[int(x[0])].copy()

    def update(self, x, a, target):
        before = self.table[int(x[0]), a]
        self.table[int(x[0]), a] = target
        self.updates.append((int(x[0]), a, target))
        return before


def chain_lesson(n, terminated=True, final_reward=1.0):
    inputs = np.arange(n + 1, dtype=float)[:, None]
    rewards = np.zeros(n)
    rewards[-1] = final_reward
    return Lesson(inputs, np.zeros(n, dtype=int), rewards, terminated=terminated, truncated=not terminated)


def test_incremental_backward_replay_propagates_in_one_pass():
    # backward order + incremental mode: the goal reward reaches the first state in one replay (3.5)
    q = TableQ(5, 2)
    replay_q(q, chain_lesson(4), ReplayParams(gamma=0.9, lam=0.0))
    assert [u[0] for u in q.updates] == [3, 2, 1, 0]
    np.testing.assert_allclose(q.table[:4, 0], [0.9**3, 0.9**2, 0.9, 1.0])


def test_truncated_lesson_bootstraps_from_its_last_state():
    q = TableQ(4, 2)
    q.table[3] = [0.5, 0.2]
    replay_q(q, chain_lesson(3, terminated=False, final_reward=0.0), ReplayParams(gamma=0.9))
    assert q.table[2, 0] == pytest.approx(0.9 * 0.5)
    q2 = TableQ(4, 2)
    q2.table[3] = [0.5, 0.2]
    replay_q(q2, chain_lesson(3, terminated=True, final_reward=0.0), ReplayParams(gamma=0.9))
    assert q2.table[2, 0] == 0.0  # a terminal last state is worth 0


def test_non_policy_actions_are_not_replayed_and_cut_lambda():
    # state 1's action 0 is clearly worse than action 1: with a high P_t it is a non-policy action
    q = TableQ(4, 2)
    q.table[1] = [0.0, 5.0]
    lesson = chain_lesson(3)
    replay_q(q, lesson, ReplayParams(gamma=1.0, lam=1.0, temperature=1.0, p_threshold=0.2))
    assert (1, 0, pytest.approx(1.0)) not in q.updates
    assert [u[0] for u in q.updates] == [2, 0]
    # x_0's target ignores e'_1 (lambda cut) and uses max Q(x_1) = 5
    assert q.table[0, 0] == pytest.approx(5.0)


def test_batch_mode_equals_lambda_returns_of_the_frozen_values():
    q = TableQ(5, 2)
    q.table[:, 0] = [0.1, 0.2, 0.3, 0.4, 0.5]
    lesson = chain_lesson(4)
    u = np.array([0.2, 0.3, 0.4, 0.0])
    expected = lambda_returns(lesson.rewards, u, 0.9, 0.6)
    replay_q(q, lesson, ReplayParams(gamma=0.9, lam=0.6, batch=True))
    np.testing.assert_allclose(q.table[:4, 0], expected)


def test_incremental_equals_batch_when_nothing_learns():
    rng = np.random.default_rng(0)
    cfg = NetConfig(3, 4, lr=1e-12, momentum=0.0)
    inputs = rng.normal(size=(6, 3))
    lesson = Lesson(inputs, rng.integers(0, 2, 5), rng.normal(size=5), terminated=True)
    a, b = PlainQ(OAON(cfg, 2, np.random.default_rng(1))), PlainQ(OAON(cfg, 2, np.random.default_rng(1)))
    ta, tb = [], []
    a.update = lambda x, act, t, f=a.update: (ta.append(t), f(x, act, t))[1]
    b.update = lambda x, act, t, f=b.update: (tb.append(t), f(x, act, t))[1]
    replay_q(a, lesson, ReplayParams(gamma=0.9, lam=0.7))
    replay_q(b, lesson, ReplayParams(gamma=0.9, lam=0.7, batch=True))
    np.testing.assert_allclose(ta, tb, rtol=1e-9)


def test_replay_ahc_moves_v_toward_the_return_and_policy_by_the_td_error():
    rng = np.random.default_rng(0)
    v = OAON(NetConfig(1, 3, lr=0.5, momentum=0.0), 1, rng)
    pol = OAON(NetConfig(1, 3, lr=0.5, momentum=0.0), 2, rng)
    lesson = Lesson(np.array([[0.5], [-0.5]]), np.array([1]), np.array([1.0]), terminated=True)
    v0, m0, m_other = v.value([0.5], 0), pol.value([0.5], 1), pol.value([0.5], 0)
    assert replay_ahc(v, pol, lesson, ReplayParams(gamma=0.9)) == 1
    assert v.value([0.5], 0) > v0 and pol.value([0.5], 1) > m0  # return 1 beats the prediction
    assert pol.value([0.5], 0) == m_other  # OAON: the other action's net is untouched



def _ahc_nets(seed=4):
    rng = np.random.default_rng(seed)
    v = OAON(NetConfig(2, 3, value_range=1.5, init_range=0.5, lr=0.4, momentum=0.9), 1, rng)
    pol = OAON(NetConfig(2, 3, init_range=0.5, lr=0.3, momentum=0.9), 2, rng)
    return v, pol


AHC_LESSON = Lesson(np.array([[0.5, -0.2], [-0.3, 0.4], [0.2, 0.7], [0.6, -0.6]]), np.array([1, 0, 1]),
                    np.array([0.2, -0.4, 0.9]), terminated=False)
AHC_PARAMS = ReplayParams(gamma=0.8, lam=0.6)


def _numpy_replay_ahc(v, pol, lesson, params):
    """Fig. 5.1(b), written out for a lesson whose actions are all policy actions: backward from the last step,
    e_t = r_t + gamma ((1 - lam) u_{t+1} + lam e_{t+1}) (lam 0 at the last step), V(x_t) moved toward e_t and the
    taken action's merit by e_t - V(x_t). Incremental: u_{t+1} = V(x_{t+1}) now; batch: V as before the lesson."""
    x, n = lesson.inputs, len(lesson)
    frozen = [v.value(x[t], 0) for t in range(n + 1)]
    e_next = 0.0
    for t in range(n - 1, -1, -1):
        u = 0.0 if (t == n - 1 and lesson.terminated) else (frozen[t + 1] if params.batch else v.value(x[t + 1], 0))
        lam = 0.0 if t == n - 1 else params.lam
        e = lesson.rewards[t] + params.gamma * ((1 - lam) * u + lam * e_next)
        v_x = v.update(x[t], 0, e)
        pol.update_error(x[t], int(lesson.actions[t]), e - v_x)
        e_next = e


@pytest.mark.parametrize("batch", [False, True])
def test_replay_ahc_gives_the_exact_weights_of_fig_5_1b(batch):
    from tests.numpy_nets import NumpyOAON

    params = ReplayParams(gamma=AHC_PARAMS.gamma, lam=AHC_PARAMS.lam, batch=batch)
    v, pol = _ahc_nets()
    v_ref, pol_ref = NumpyOAON(v), NumpyOAON(pol)
    assert replay_ahc(v, pol, AHC_LESSON, params) == 3
    _numpy_replay_ahc(v_ref, pol_ref, AHC_LESSON, params)
    v_ref.assert_same(v)
    pol_ref.assert_same(pol)


def test_replay_ahc_batch_mode_differs_from_incremental():
    nets = {}
    for batch in (False, True):
        v, pol = _ahc_nets()
        replay_ahc(v, pol, AHC_LESSON, ReplayParams(gamma=0.8, lam=0.6, batch=batch))
        nets[batch] = (v.w1.copy(), pol.w2.copy())
    assert not np.allclose(nets[False][0], nets[True][0]) and not np.allclose(nets[False][1], nets[True][1])


def test_replay_ahc_batch_mode_judges_non_policy_actions_before_the_lesson():
    # a greedy policy (T = 0) with P_t 0.5: only the actions the policy net preferred before the lesson are replayed,
    # and lambda is cut before a non-policy action (the targets of ahc_batch_targets)
    v, pol = _ahc_nets()
    x = AHC_LESSON.inputs
    merits = np.array([pol.values(x[t]) for t in range(3)])
    params = ReplayParams(gamma=0.8, lam=0.6, temperature=0.0, p_threshold=0.5, batch=True)
    greedy = merits.argmax(axis=1) == AHC_LESSON.actions
    assert replay_ahc(v, pol, AHC_LESSON, params) == greedy.sum()
    targets, policy = replay_module.ahc_batch_targets([0.0, 0.1, 0.2, 0.3], merits, AHC_LESSON.actions,
                                                      AHC_LESSON.rewards, False, params)
    np.testing.assert_array_equal(policy, greedy)
    lams = np.where(np.append(greedy[1:], False), 0.6, 0.0)
    np.testing.assert_allclose(targets, lambda_returns(AHC_LESSON.rewards, [0.1, 0.2, 0.3], 0.8, lams), rtol=1e-15)


# ---------------------------------------------------------------------------- batch targets (5.1.2, 7.5)

def test_batch_targets_by_hand():
    # 3 steps; the action at t=1 is non-policy (prob below threshold): not replayed and lambda cut at t=0.
    values = np.array([[0.2, 0.1], [0.0, 5.0], [0.3, 0.6], [0.4, 0.9]])
    actions = np.array([0, 0, 1])
    rewards = np.array([0.0, 0.0, 1.0])
    params = ReplayParams(gamma=0.9, lam=0.5, temperature=1.0, p_threshold=0.01)
    targets, policy = batch_targets(values, actions, rewards, True, params)
    assert boltzmann_probabilities(values[1], 1.0)[0] < 0.01
    assert policy.dtype == bool and policy.tolist() == [True, False, True]
    e2 = 1.0  # terminal: u = 0, lambda 0 at the last step
    e1 = 0.9 * (0.5 * 0.6 + 0.5 * e2)  # u_2 = max Q(x_2) = 0.6
    e0 = 0.9 * 5.0  # lambda cut: a_1 is non-policy, so e'_0 = r_0 + gamma u_1
    assert np.allclose(targets, [e0, e1, e2])
    # a truncated lesson bootstraps from the last input; lambda_returns agrees with p_threshold 0
    t2, w2 = batch_targets(values, actions, rewards, False, ReplayParams(gamma=0.9, lam=0.5))
    assert np.allclose(t2, lambda_returns(rewards, values[1:].max(1), 0.9, 0.5)) and w2.all()


def test_batch_targets_with_weights_and_allowed_by_hand():
    # Ch. 8's batch replay over behaviours: W of Eq. 6.6 decides the non-policy test, ``allowed`` the target's max.
    values = np.array([[0.0, 0.0], [1.0, 3.0], [2.0, 0.5]])
    actions, rewards = np.array([0, 1]), np.array([0.0, 0.0])
    params = ReplayParams(gamma=0.5, lam=0.5, temperature=0.1, p_threshold=0.05)
    # step 1: action 1 has P ~ 1 by exp(Q/T) alone; W = (1, 0) rules it out, so it is non-policy and cuts lambda
    allowed = np.array([[1, 1], [1, 0], [0, 0]], dtype=bool)  # at x_1 only action 0; at x_2 none, so all
    targets, policy = batch_targets(values, actions, rewards, False, params,
                                    weights=np.array([[1.0, 1.0], [1.0, 0.0]]), allowed=allowed)
    assert policy.tolist() == [True, False]
    e1 = 0.0 + 0.5 * 2.0  # u_2 = max over all (none allowed)
    e0 = 0.0 + 0.5 * 1.0  # u_1 = Q(x_1, 0), the one allowed; lambda cut by the non-policy step 1
    assert np.allclose(targets, [e0, e1])
    t_free, p_free = batch_targets(values, actions, rewards, False, params)
    assert p_free.tolist() == [True, True] and np.isclose(t_free[0], 0.5 * (0.5 * 3.0 + 0.5 * t_free[1]))


@pytest.mark.parametrize("weighted", [False, True])
def test_policy_mask_equals_the_per_step_test(weighted):
    rng = np.random.default_rng(4)
    values, actions = rng.normal(0, 30, (200, 4)), rng.integers(0, 4, 200)
    weights = rng.choice([0.0, 1.0, 100.0], (200, 4)) if weighted else None
    if weighted:
        weights[np.arange(200), actions] = np.maximum(weights[np.arange(200), actions], 1.0)
        weights[::7, actions[::7]] = 0.0
        weights[~(weights > 0).any(axis=1), 0] = 1.0
    params = ReplayParams(gamma=0.9, temperature=5.0, p_threshold=0.02)
    ref = [is_policy_action(values[t], int(actions[t]), params, None if weights is None else weights[t])
           for t in range(200)]
    mask = policy_mask(values, actions, params, weights)
    assert mask.tolist() == ref and 0 < mask.sum() < 200


def test_batch_targets_checks_shapes():
    with pytest.raises(ValueError, match="n\\+1=3"):
        batch_targets(np.zeros((2, 2)), np.array([0, 1]), np.zeros(2), True, ReplayParams(gamma=0.9))


# ---------------------------------------------------------------------------------- the repairs of 5.4.3

class _Table:
    """A tabular Q-function (for exact repair arithmetic): update sets Q(a) += 0.5 (target - Q(a))."""

    n_actions = 3

    def __init__(self, v):
        self.v = np.array(v, dtype=float)
        self.calls = []

    def values(self, x):
        return self.v.copy()

    def update(self, x, a, target):
        self.calls.append((a, target))
        before = self.v[a]
        self.v[a] += 0.5 * (target - before)
        return before


def test_lower_repair_lowers_every_overvalued_other_action():
    q = _Table([1.0, 5.0, 3.0])
    assert repair_step(q, None, 0, "lower") == 2
    assert q.calls == [(1, 1.0), (2, 1.0)]  # error Q(x,a1) - Q(x,a_i) through net a_i (5.4.3)
    np.testing.assert_allclose(q.v, [1.0, 3.0, 2.0])


def test_raise_repair_raises_taught_action_to_the_best_other():
    q = _Table([1.0, 5.0, 3.0])
    assert repair_step(q, None, 0, "raise") == 1
    assert q.calls == [(0, 5.0)]
    np.testing.assert_allclose(q.v, [3.0, 5.0, 3.0])


def test_no_repair_when_condition_holds():
    for mode in REPAIRS:
        q = _Table([6.0, 5.0, 3.0])
        assert repair_step(q, None, 0, mode) == 0
        assert q.calls == []
    with pytest.raises(ValueError, match="repair must be one of"):
        repair_step(_Table([0, 0, 0]), None, 0, "sideways")


# ------------------------------------------------------------------- the compiled kernel vs the plain loop
#
# ``replay_oaon`` (connrl.core.replay_kernel) is compared with ``replay_q_reference``, the readable loop of
# Fig. 5.1(a), never with ``replay_q`` on an OAON: that dispatches to the kernel itself.

def _lesson(rng, n=12, d=7, terminated=True):
    return Lesson(rng.uniform(-0.5, 1.0, (n + 1, d)), rng.integers(0, 4, n), rng.choice([0.0, -10.0, 100.0], n),
                  terminated=terminated, truncated=not terminated)


def _pair(hidden, d=7, n_actions=4, **kw):
    kw = {"value_range": 100.0, "init_range": 0.5, "lr": 0.05, "momentum": 0.9 if hidden else 0.0, **kw}
    cfg = NetConfig(d, hidden, **kw)
    return OAON(cfg, n_actions, np.random.default_rng(3)), OAON(cfg, n_actions, np.random.default_rng(3))


def _assert_same_nets(fast, ref):
    np.testing.assert_allclose(fast.w2, ref.w2, atol=1e-12)
    np.testing.assert_allclose(fast.w1, ref.w1, atol=1e-12)
    np.testing.assert_allclose(fast.d2, ref.d2, atol=1e-12)  # momentum terms too
    np.testing.assert_allclose(fast.d1, ref.d1, atol=1e-12)


@pytest.mark.parametrize("hidden", [5, 0])
@pytest.mark.parametrize("terminated", [True, False])
@pytest.mark.parametrize("p_threshold", [0.0, 0.2])
def test_kernel_equals_reference_replay(hidden, terminated, p_threshold):
    rng = np.random.default_rng(0)
    lesson = _lesson(rng, terminated=terminated)
    fast, ref = _pair(hidden)
    params = ReplayParams(gamma=0.9, lam=0.7, temperature=10.0, p_threshold=p_threshold, clip=None)
    used = replay_oaon(fast, lesson, params)
    assert used == replay_q_reference(ref, lesson, params)  # the plain loop
    assert (used < len(lesson)) == (p_threshold > 0)  # P_t > 0 left some non-policy experiences out
    _assert_same_nets(fast, ref)


@pytest.mark.parametrize("hidden", [5, 0])
def test_kernel_reusing_the_policy_tests_values_is_exact(hidden):
    # with P_t > 0 the kernel takes each next state's values from the policy test one step later and computes only
    # the updated net again; a threshold every step passes updates exactly as P_t = 0 (values computed afresh), so
    # the two nets must agree to the last bit (the reference comparison above allows 1e-12)
    rng = np.random.default_rng(4)
    lesson = _lesson(rng, n=40, terminated=False)
    fresh, reused = _pair(hidden)
    assert replay_oaon(fresh, lesson, ReplayParams(gamma=0.9, lam=0.7, temperature=10.0, p_threshold=0.0)) == 40
    assert replay_oaon(reused, lesson, ReplayParams(gamma=0.9, lam=0.7, temperature=10.0, p_threshold=1e-300)) == 40
    for a, b in ((fresh.w1, reused.w1), (fresh.w2, reused.w2), (fresh.d1, reused.d1), (fresh.d2, reused.d2)):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("repair", ["lower", "raise"])
@pytest.mark.parametrize("hidden", [5, 0])
@pytest.mark.parametrize("terminated, p_threshold", [(True, 0.0), (False, 0.0), (True, 0.2), (False, 0.2)])
def test_kernel_repairs_equal_reference(repair, hidden, terminated, p_threshold):
    rng = np.random.default_rng(1)
    lesson = _lesson(rng, terminated=terminated)
    fast, ref = _pair(hidden)
    params = ReplayParams(gamma=0.9, lam=0.7, temperature=10.0, p_threshold=p_threshold)
    assert replay_oaon(fast, lesson, params, REPAIRS.index(repair)) == replay_q_reference(ref, lesson, params, repair)
    _assert_same_nets(fast, ref)
    plain, _ = _pair(hidden)
    replay_q_reference(plain, lesson, params)
    assert not np.allclose(plain.w2, ref.w2)  # the repairs did change the nets


def test_kernel_first_update_target_is_td_lambda_return():
    # one-step terminated lesson: target = r; the update moves Q(x0, a0) toward r exactly as OAON.update does
    x = np.array([[0.3, -0.2], [0.1, 0.4]])
    lesson = Lesson(x, np.array([1]), np.array([100.0]), terminated=True)
    fast, ref = _pair(3, d=2, n_actions=2)
    replay_oaon(fast, lesson, ReplayParams(gamma=0.9, lam=0.7))
    ref.update(x[0], 1, 100.0)
    np.testing.assert_array_equal(fast.w2, ref.w2)


@pytest.mark.parametrize("hidden, p_threshold, clip, terminated, temperature, linear", [
    (5, 0.0, None, True, 0.3, False), (5, 0.3, 1.0, False, 0.3, False), (0, 0.2, None, True, 0.3, False),
    (0, 0.2, 0.5, False, 0.3, True),  # the linear perceptron of 7.4, clipped targets
    (5, 0.2, None, False, 0.0, False),  # T = 0: only greedy actions (ties shared) are policy actions
])
def test_compiled_replay_matches_the_python_loop(hidden, p_threshold, clip, terminated, temperature, linear):
    rng = np.random.default_rng(5)
    lesson = Lesson(rng.normal(size=(31, 6)), rng.integers(0, 3, 30), rng.normal(size=30), terminated=terminated)
    params = ReplayParams(gamma=0.9, lam=0.7, temperature=temperature, p_threshold=p_threshold, clip=clip)
    cfg = NetConfig(6, hidden, lr=0.1, momentum=0.9 if hidden else 0.0, init_range=0.5, linear_output=linear)
    fast, slow = OAON(cfg, 3, np.random.default_rng(1)), OAON(cfg, 3, np.random.default_rng(1))
    n_fast = replay_oaon(fast, lesson, params)
    n_slow = replay_q_reference(slow, lesson, params)
    assert n_fast == n_slow
    np.testing.assert_allclose(fast.w2, slow.w2, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(fast.w1, slow.w1, rtol=1e-9, atol=1e-12)


# ------------------------------------------------------------------------------------- dispatch of replay_q

def test_the_oaon_kernel_is_the_registered_fast_path():
    assert replay_module.FAST_PATHS[OAON] is replay_oaon


@pytest.mark.parametrize("repair", REPAIRS)
def test_replay_q_on_an_oaon_uses_the_registered_fast_path(monkeypatch, repair):
    calls, options = [], []

    def spy(q, lesson, params, repair_index, weights, allowed, discounts):
        calls.append((q, lesson, params, repair_index))
        options.append((weights, allowed, discounts))
        return 123

    monkeypatch.setitem(replay_module.FAST_PATHS, OAON, spy)
    monkeypatch.setattr(replay_module, "replay_q_reference", _must_not_run)
    net, _ = _pair(5)
    lesson = _lesson(np.random.default_rng(0))
    params = ReplayParams(gamma=0.9, lam=0.7)
    assert replay_q(net, lesson, params, repair) == 123
    assert calls == [(net, lesson, params, REPAIRS.index(repair))]
    w, m, d = np.ones((len(lesson), 4)), np.ones((len(lesson) + 1, 4), bool), np.full(len(lesson), 0.5)
    assert replay_q(net, lesson, params, repair, weights=w, allowed=m, discounts=d) == 123
    assert options[0] == (None, None, None) and all(a is b for a, b in zip(options[1], (w, m, d), strict=True))
    calls.pop()
    with pytest.raises(ValueError, match="repair must be one of"):
        replay_q(net, lesson, params, "sideways")
    assert len(calls) == 1


def _must_not_run(*args, **kwargs):
    raise AssertionError("the reference loop ran")


def _fast_path_must_not_run(*args, **kwargs):
    raise AssertionError("the fast path ran")


@pytest.mark.parametrize("how", ["fast=False", "batch", "other type"])
def test_replay_q_falls_back_to_the_reference_loop(monkeypatch, how):
    calls = []

    def reference(q, lesson, params, repair="none", weights=None, allowed=None, discounts=None):
        calls.append((q, lesson, params, repair))
        return 7

    monkeypatch.setitem(replay_module.FAST_PATHS, OAON, _fast_path_must_not_run)
    monkeypatch.setattr(replay_module, "replay_q_reference", reference)
    net, _ = _pair(5)
    lesson = _lesson(np.random.default_rng(0))
    params = ReplayParams(gamma=0.9, lam=0.7, batch=how == "batch")
    q = PlainQ(net) if how == "other type" else net
    assert replay_q(q, lesson, params, "none", fast=how != "fast=False") == 7
    assert calls == [(q, lesson, params, "none")]


class PlainQ:
    """Hides the OAON type so replay_q has no fast path for it and runs the reference loop."""

    def __init__(self, net):
        self.net, self.n_actions = net, net.n_nets

    def values(self, x):
        return self.net.values(x)

    def update(self, x, a, t):
        return self.net.update(x, a, t)


def test_weighted_replay_drops_the_steps_whose_choice_was_ruled_out():
    """Ch. 6: with W = 1 everywhere Eq. 6.6 is Eq. 3.4 and the replay is unchanged; a step whose taken action had
    W = 0 (not applicable) has probability 0 < P_t, so it is not replayed and lambda restarts there."""
    lesson = _lesson(np.random.default_rng(3))
    params = ReplayParams(gamma=0.99, lam=0.8, temperature=5.0, p_threshold=0.01)
    a, b = _pair(5)
    used_plain = replay_q_reference(a, lesson, params)
    used_ones = replay_q_reference(b, lesson, params, weights=np.ones((len(lesson), 4)))
    assert used_plain == used_ones
    np.testing.assert_array_equal(a.w1, b.w1)
    w = np.ones((len(lesson), 4))
    w[[2, 5], lesson.actions[[2, 5]]] = 0.0
    c, _ = _pair(5)
    assert replay_q_reference(c, lesson, params, weights=w) == used_plain - 2


@pytest.mark.parametrize("temperature", [5.0, 0.0])
@pytest.mark.parametrize("hidden", [5, 0])
@pytest.mark.parametrize("options", ["weights", "allowed", "discounts", "all"])
def test_kernel_per_step_options_equal_reference(hidden, options, temperature):
    """Ch. 6's per-step options (Eq. 6.6 weights, a max over allowed choices, per-step discounts) in the kernel
    match the plain loop."""
    rng = np.random.default_rng(7)
    lesson = _lesson(rng, n=20, terminated=False)
    w = rng.choice([0.0, 1.0, 100.0], (20, 4))
    w[np.arange(20), rng.integers(0, 4, 20)] = 1.0  # never all zero
    kw = {"weights": w, "allowed": rng.random((21, 4)) < 0.5, "discounts": 0.99 ** rng.integers(1, 12, 20)}
    kw = kw if options == "all" else {options: kw[options]}
    fast, ref = _pair(hidden)
    params = ReplayParams(gamma=0.99, lam=0.8, temperature=temperature, p_threshold=0.02)
    assert replay_oaon(fast, lesson, params, 0, **kw) == replay_q_reference(ref, lesson, params, **kw)
    _assert_same_nets(fast, ref)
    plain, _ = _pair(hidden)
    replay_q_reference(plain, lesson, params)
    assert not np.allclose(plain.w2, ref.w2)  # the option did change the replay


def test_allowed_and_discounts_targets_by_hand():
    """A 2-step lesson into a table: the target of step 0 is r0 + d0 * max over the allowed actions of Q(x1)."""
    x = np.array([[0.0], [1.0], [2.0]])
    lesson = Lesson(x, np.array([0, 1]), np.array([1.0, 0.0]), terminated=False, truncated=True)
    q = _StateTable([[0.0, 0.0], [5.0, 50.0], [2.0, 3.0]])
    allowed = np.array([[True, True], [True, False], [True, True]])
    replay_q_reference(q, lesson, ReplayParams(gamma=0.9, lam=0.0), allowed=allowed, discounts=np.array([0.5, 0.9]))
    # backward: step 1 target 0 + 0.9 * max(2, 3); step 0 target 1 + 0.5 * 5 (50 is not allowed)
    assert q.calls == [(1, 1, pytest.approx(2.7)), (0, 0, pytest.approx(3.5))]
    with pytest.raises(ValueError, match="allowed must have 3 rows"):
        replay_q_reference(q, lesson, ReplayParams(gamma=0.9), allowed=allowed[:2])


class _StateTable:
    """A table indexed by the input's single value; updates are only recorded."""

    n_actions = 2

    def __init__(self, v):
        self.v, self.calls = np.array(v, dtype=float), []

    def values(self, x):
        return self.v[int(x[0])].copy()

    def update(self, x, a, target):
        self.calls.append((int(x[0]), a, target))
        return self.v[int(x[0]), a]


def _grouped(rng, n=30, terminated=False):
    """A lesson of a slow random walk (so state grouping merges steps) and its grouping (6.6.4)."""
    from connrl.core.grouping import group_lesson

    x = np.cumsum(rng.normal(scale=0.3, size=(n + 1, 7)), axis=0) * 0.2
    lesson = Lesson(x, np.repeat(rng.integers(0, 4, n // 3 + 1), 3)[:n], rng.choice([0.0, -10.0, 100.0], n),
                    terminated=terminated, truncated=not terminated)
    w = rng.choice([1.0, 100.0], (n, 4))
    allowed = rng.random((n + 1, 4)) < 0.7
    g = group_lesson(lesson, 0.99, (0.5, 2.5), rng, w, allowed)
    assert len(g.lesson) < n and g.discounts.min() < 0.99  # some steps were grouped
    return g


@pytest.mark.parametrize("hidden", [5, 0])
@pytest.mark.parametrize("terminated", [True, False])
def test_kernel_equals_reference_on_a_grouped_lesson(hidden, terminated):
    """State grouping's replay (what QCON.replay_lesson passes): the compiled kernel and the plain loop agree."""
    g = _grouped(np.random.default_rng(11), terminated=terminated)
    fast, ref = _pair(hidden)
    params = ReplayParams(gamma=0.99, lam=0.8, temperature=2.0, p_threshold=0.02)
    kw = {"weights": g.weights, "allowed": g.allowed, "discounts": g.discounts}
    assert replay_q(fast, g.lesson, params, **kw) == replay_q_reference(ref, g.lesson, params, **kw)
    _assert_same_nets(fast, ref)


class _Recorder:
    """Fixed Q-values per input row (keyed by its first input); updates are only recorded."""

    def __init__(self, inputs, rng):
        self.v = {float(x[0]): rng.normal(size=4) for x in inputs}
        self.calls = []

    def values(self, x):
        return self.v[float(x[0])].copy()

    def update(self, x, a, target):
        self.calls.append(target)
        return self.v[float(x[0])][a]


@pytest.mark.parametrize("batch", [False, True])
def test_grouped_replay_targets_are_lambda_returns_with_per_step_discounts(batch):
    """With fixed values and every action a policy action, replaying a grouped lesson (incremental or batch)
    updates toward ``lambda_returns`` with the per-step discounts gamma^k."""
    rng = np.random.default_rng(5)
    g = _grouped(rng, terminated=True)
    q = _Recorder(g.lesson.inputs, rng)
    params = ReplayParams(gamma=0.99, lam=0.8, p_threshold=0.0, batch=batch)
    replay_q_reference(q, g.lesson, params, discounts=g.discounts)
    u = np.array([q.values(x).max() for x in g.lesson.inputs[1:]])
    u[-1] = 0.0  # terminal
    expected = lambda_returns(g.lesson.rewards, u, g.discounts, 0.8)
    np.testing.assert_allclose(q.calls[::-1], expected, rtol=1e-12)
    assert not np.allclose(expected, lambda_returns(g.lesson.rewards, u, 0.99, 0.8))  # the discounts mattered
    with pytest.raises(ValueError, match="repairs are defined for incremental replay only"):
        replay_q_reference(q, g.lesson, ReplayParams(gamma=0.99, batch=True), repair="lower")


@pytest.mark.parametrize("dtype", [np.int64, np.int32])
def test_a_lesson_whose_actions_do_not_fit_is_refused_before_the_kernel(dtype):
    """``check_lesson_fits`` (compiled for int64 actions) refuses an action outside 0..A-1 wherever it sits."""
    from connrl.core.replay import check_lesson_fits
    x = np.zeros((5, 3))
    check_lesson_fits(Lesson(x, np.array([0, 1, 2, 1], dtype=dtype), np.zeros(4), True), 3, 3)
    check_lesson_fits(Lesson(x[:1], np.array([], dtype=dtype), np.zeros(0), True), 3, 3)
    for bad in ([0, 1, 3, 1], [-1, 0, 0, 0], [0, 0, 0, 7]):
        with pytest.raises(ValueError, match="does not fit nets of actions 0..2"):
            check_lesson_fits(Lesson(x, np.array(bad, dtype=dtype), np.zeros(4), True), 3, 3)
    with pytest.raises(ValueError, match="on 4 inputs"):
        check_lesson_fits(Lesson(x, np.array([0, 1, 2, 1], dtype=dtype), np.zeros(4), True), 3, 4)


def test_replay_params_are_kept_per_temperature_and_threshold():
    """A trial's replays share their parameters; a new temperature, threshold or base gives new ones."""
    from connrl.agents.base import ReplayConfig
    from connrl.agents.qcon import QCON, QCONConfig
    from connrl.core.exploration import TemperatureSchedule
    agent = QCON(QCONConfig(NetConfig(3, 2), TemperatureSchedule.direct(0.5, 0.1, 5), replay=ReplayConfig()), 2,
                 np.random.default_rng(0))
    agent.explore.begin(0)
    p = agent.replay_params(0.1)
    assert agent.replay_params(0.1) is p and (p.temperature, p.p_threshold) == (0.5, 0.1)
    assert agent.replay_params(0.2).p_threshold == 0.2 and agent.replay_params(0.1) is p
    agent.explore.begin(4)
    assert agent.replay_params(0.1).temperature == pytest.approx(0.1) and agent.replay_params(0.1) is not p
    agent._replay = ReplayParams(gamma=0.5)
    assert agent.replay_params(0.1).gamma == 0.5


def test_the_kept_discounts_and_empty_arrays_stay_what_they_stand_for():
    """Replays of long and short lessons under two gammas leave the shared arrays as ``np.full`` / ``np.zeros``."""
    from connrl.core import replay_kernel
    rng = np.random.default_rng(9)
    net = OAON(NetConfig(3, 2), 2, rng)
    for n, gamma in ((300, 0.9), (5, 0.9), (700, 0.5), (3, 0.5), (400, 0.9)):
        lesson = Lesson(rng.normal(size=(n + 1, 3)), rng.integers(0, 2, n), rng.normal(size=n), False)
        replay_oaon(net, lesson, ReplayParams(gamma=gamma, lam=0.5))
        np.testing.assert_array_equal(replay_kernel._gammas(n, gamma), np.full(n, gamma))
    for gamma, d in replay_kernel._GAMMAS.items():
        np.testing.assert_array_equal(d, np.full(d.size, gamma))
    for (a, dtype), z in replay_kernel._NONE.items():
        assert z.shape == (0, a) and z.dtype == dtype
