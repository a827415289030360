"""Memory architectures of Ch. 7: window encoding, recurrent-Q replay, and that what an agent sees while
acting is exactly what replay reconstructs."""

import copy

import numpy as np
import pytest

from connrl.agents.base import LinearSchedule, ReplayConfig
from connrl.agents.memory import (
    RecurrentModelConfig,
    RecurrentModelQ,
    RecurrentQ,
    RecurrentQConfig,
    SensationWindow,
    WindowQ,
    model_targets,
    replay_recurrent_q,
    window_input_size,
)
from connrl.agents.qcon import QCONConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.core.lessons import Lesson
from connrl.core.replay import ReplayParams, batch_targets
from connrl.core.rollout import run_trial
from connrl.envs.cup import CupCollectionEnv
from connrl.nets import NetConfig, RecurrentNetConfig, RecurrentOAON
from connrl.tasks.hidden_state import _probe_walks

TEMP = TemperatureSchedule.inverse(5, 30, 100)


REPLAY = ReplayConfig(capacity=70, lessons_per_trial=LinearSchedule(3, 3), p_threshold=0.01,
                      p_threshold_oldest=1e-5)


def window_agent(seed=0, window=2):
    net = NetConfig(window_input_size(4, 3, window), 0, lr=0.02, init_range=0.5, momentum=0.0)
    cfg = QCONConfig(net=net, temperature=TEMP, lam=0.8, replay=REPLAY)
    return WindowQ(cfg, 3, np.random.default_rng(seed), n_sensation=4, window=window)


def recurrent_q_agent(seed=0):
    net = RecurrentNetConfig(4, 6, 3, 1, lr=0.04)
    return RecurrentQ(RecurrentQConfig(net=net, temperature=TEMP, lam=0.8, replay=REPLAY), 3,
                      np.random.default_rng(seed))


def model_agent(seed=0):
    model = RecurrentNetConfig(4, 8, 5, 5, lr=0.02)
    q_net = NetConfig(9, 4, lr=0.2, init_range=0.5)
    cfg = RecurrentModelConfig(model=model, q_net=q_net, temperature=TEMP, lam=0.8, replay=REPLAY,
                               model_lessons_per_trial=3)
    return RecurrentModelQ(cfg, 3, np.random.default_rng(seed))


# ------------------------------------------------------------------------------------------- window-Q

def test_window_encoding_by_hand():
    w = SensationWindow(2, 3, 2)
    s0, s1, s2 = np.array([0.5, -0.5]), np.array([-0.5, -0.5]), np.array([0.5, 0.5])
    assert np.array_equal(w.encode(s0), np.r_[s0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0])  # empty slots are 0
    w.push(s0, 1)
    w.push(s1, 2)
    expected = np.r_[s2, s1, s0, -0.5, -0.5, 0.5, -0.5, 0.5, -0.5]  # newest first; actions one-hot +-0.5
    assert np.array_equal(w.encode(s2), expected)
    assert window_input_size(2, 3, 2) == expected.size
    w.reset()
    assert not w.encode(s2)[2:].any()


def test_window_q_rejects_wrong_input_size():
    cfg = QCONConfig(net=NetConfig(10, 0), temperature=TEMP)
    with pytest.raises(ValueError, match="n_inputs=39"):
        WindowQ(cfg, 3, np.random.default_rng(0), n_sensation=4, window=5)


@pytest.mark.parametrize("make", [window_agent, recurrent_q_agent, model_agent])
def test_act_rejects_a_bad_forced_action(make):
    agent = make()
    env = CupCollectionEnv()
    obs, info = env.reset(seed=0)
    agent.begin_trial(obs, info, learning=False)
    with pytest.raises(ValueError, match="force"):
        agent.act(obs, info, greedy=True, force=3)


def _scripted_inputs(agent, actions, learning):
    """Network inputs the agent used at each act() of a scripted trial (forced actions)."""
    env = CupCollectionEnv()
    obs, info = env.reset(seed=0, options={"instance": "A"})
    agent.begin_trial(obs, info, learning=learning)
    seen = []
    for a in actions:
        got = agent.act(obs, info, greedy=not learning, force=a)
        assert got == a
        seen.append(agent._x.copy())
        obs, r, term, trunc, info = env.step(a)
        if learning:
            agent.observe(a, r, obs, term, trunc, info)
    agent.end_trial()
    return np.array(seen)


def test_window_q_sees_the_same_window_in_learning_and_test_trials():
    actions = [1, 2, 1, 0, 0, 1, 1]
    learn = _scripted_inputs(window_agent(), actions, learning=True)
    test = _scripted_inputs(window_agent(), actions, learning=False)
    assert np.array_equal(learn, test)
    # act 2 (after the pick-up at cell 3): window = sensations at cell 3 and cell 2, actions pick-up, right
    assert np.array_equal(learn[2][4:12], np.r_[-0.5, -0.5, -0.5, -0.5, -0.5, 0.5, -0.5, -0.5])
    assert np.array_equal(learn[2][12:], np.r_[-0.5, -0.5, 0.5, -0.5, 0.5, -0.5])
    agent = window_agent()  # the lessons store the windowed inputs that were acted on
    _scripted_inputs(agent, actions, learning=True)
    assert np.array_equal(agent.book.memory.lessons[-1].inputs[:-1], learn)


def test_replay_recurrent_q_is_one_bptt_step_toward_the_targets():
    rng = np.random.default_rng(1)
    net = RecurrentOAON(RecurrentNetConfig(4, 6, 3, 1, lr=0.04, momentum=0.0), 3, rng)
    lesson = Lesson(rng.choice([-0.5, 0.5], (6, 4)), rng.integers(0, 3, 5), np.r_[0, 0, 0, 0, 1.0], True)
    params = ReplayParams(gamma=0.9, lam=0.8)
    ys, _ = net.forward_sequence(lesson.inputs, np.append(lesson.actions, 0))
    targets, weights = batch_targets(ys[:, :, 0], lesson.actions, lesson.rewards, True, params)
    twin = RecurrentOAON(net.config, 3, np.random.default_rng(9))
    twin.load_state_dict(net.state_dict())
    used = replay_recurrent_q(net, lesson, params)
    twin.train_sequence(lesson.inputs[:-1], lesson.actions, targets, weights.astype(float))
    assert used == 5
    assert np.array_equal(net.w1, twin.w1) and np.array_equal(net.w2, twin.w2)
    after, _ = net.forward_sequence(lesson.inputs, np.append(lesson.actions, 0))
    taken = np.arange(5), lesson.actions
    assert np.abs(after[:-1, :, 0][taken] - targets).sum() < np.abs(ys[:-1, :, 0][taken] - targets).sum()


@pytest.mark.parametrize("share_output", [False, True])
@pytest.mark.parametrize("params", [
    ReplayParams(gamma=0.9, lam=0.8, temperature=0.05, p_threshold=0.01, batch=True),
    ReplayParams(gamma=0.9, lam=0.0, temperature=0.3, p_threshold=0.3, batch=True),  # many non-policy steps
    ReplayParams(gamma=0.95, lam=1.0, temperature=0.0, p_threshold=0.6, batch=True),  # greedy; a tie is 0.5 each
    ReplayParams(gamma=0.9, lam=0.5, batch=True, clip=0.2),  # every step replayed, targets truncated
    ReplayParams(gamma=0.9, lam=0.6, temperature=0.1, p_threshold=0.3, batch=True, clip=0.5),  # cuts and clips
])
def test_compiled_recurrent_replay_equals_the_composed_reference(params, share_output):
    """The one-call kernel against batch_targets + train_sequence, over lessons in a row (momentum carries)."""
    rng = np.random.default_rng(5)
    cfg = RecurrentNetConfig(4, 7, 3, 1, lr=0.3, momentum=0.9, share_output=share_output)
    fast = RecurrentOAON(cfg, 3, np.random.default_rng(2))
    ref = RecurrentOAON(cfg, 3, np.random.default_rng(2))
    if params.temperature == 0 and params.p_threshold > 0:  # all three nets alike: every step of the first lesson
        for net in (fast, ref):  # is a three-way tie at the max, shared by the greedy test (1/3 < P_t: not replayed)
            net.w1[1:] = net.w1[0]
            net.w2[:] = net.w2[0]
    used = steps = 0
    for k in range(6):
        n = int(rng.integers(1, 12))
        lesson = Lesson(rng.choice([-0.5, 0.5], (n + 1, 4)), rng.integers(0, 3, n),
                        rng.choice([0.0, 0.0, 1.0, -1.0], n), bool(k % 2))
        u_fast = replay_recurrent_q(fast, lesson, params)
        u_ref = replay_recurrent_q(ref, lesson, params, fast=False)
        assert u_fast == u_ref
        if params.temperature == 0 and params.p_threshold > 0 and k == 0:
            assert u_ref == 0  # ties shared: had the kernel given a tie all the mass, it would have replayed them
            for net in (fast, ref):  # then break the tie, so that later lessons replay
                net.w1[2] += np.random.default_rng(7).uniform(-0.5, 0.5, net.w1[2].shape)
        used, steps = used + u_ref, steps + n
        for name in ("w1", "w2", "d1", "d2"):
            np.testing.assert_allclose(getattr(fast, name), getattr(ref, name), rtol=0, atol=1e-12)
    assert 0 < used <= steps
    assert used == steps if params.p_threshold == 0 else params.p_threshold < 0.3 or used < steps
    with pytest.raises(ValueError, match="temperature must be >= 0"):
        fast.replay_q_lesson(np.zeros((2, 4)), [0], [0.0], True, gamma=0.9, lam=0.8, temperature=-1.0,
                             p_threshold=0.1)


@pytest.mark.parametrize("params", [
    ReplayParams(gamma=0.9, lam=0.8, temperature=0.05, p_threshold=0.01, batch=True),
    ReplayParams(gamma=0.9, lam=0.7, temperature=0.2, p_threshold=0.3, batch=True, clip=0.5),  # many cut
    ReplayParams(gamma=0.95, lam=0.9, temperature=0.0, p_threshold=0.6, batch=True),  # greedy among the allowed
])
def test_compiled_recurrent_replay_with_weights_and_allowed_choices_equals_the_reference(params):
    """Ch. 8's replay over behaviours (Eq. 6.6's W per step, each state's max over its applicable behaviours): the one
    kernel against batch_targets + train_sequence, bit for bit, over lessons in a row."""
    rng = np.random.default_rng(11)
    cfg = RecurrentNetConfig(4, 7, 3, 1, lr=0.3, momentum=0.9)
    fast, ref = (RecurrentOAON(cfg, 4, np.random.default_rng(3)) for _ in range(2))
    used = steps = 0
    for k in range(8):
        n = int(rng.integers(1, 14))
        lesson = Lesson(rng.choice([-0.5, 0.5], (n + 1, 4)), rng.integers(0, 4, n),
                        rng.choice([0.0, 0.0, 1.0, -1.0], n), bool(k % 2))
        w = rng.choice([0.0, 1.0, 1.0, 100.0], (n, 4))
        w[np.arange(n), lesson.actions] = rng.choice([1.0, 100.0], n)  # the taken choice was allowed
        ok = rng.random((n + 1, 4)) < 0.6
        ok[rng.random(n + 1) < 0.2] = False  # a state with none allowed: the max is over all
        u_fast = replay_recurrent_q(fast, lesson, params, w, ok)
        u_ref = replay_recurrent_q(ref, lesson, params, w, ok, fast=False)
        assert u_fast == u_ref
        used, steps = used + u_ref, steps + n
        for name in ("w1", "w2", "d1", "d2"):
            np.testing.assert_array_equal(getattr(fast, name), getattr(ref, name))
    assert 0 < used < steps  # some steps are cut by the test, some replayed
    with pytest.raises(ValueError, match="weights must be"):
        replay_recurrent_q(fast, lesson, params, np.zeros((n, 4)), ok)
    with pytest.raises(ValueError, match="allowed must be"):
        replay_recurrent_q(fast, lesson, params, w, ok[:-1])


def test_recurrent_q_acts_on_the_contexts_replay_reconstructs():
    agent = recurrent_q_agent(seed=3)
    env = CupCollectionEnv()
    env.reset(seed=3)
    seen = []
    orig = agent.net.values

    def spy(x):
        q = orig(x)
        seen.append(q.copy())
        return q

    agent.net.values = spy
    run_trial(env, agent, trial=0, learning=True)  # learn() changes weights after the trial ...
    lesson = agent.book.memory.lessons[-1]
    agent2 = recurrent_q_agent(seed=3)  # ... so compare with an untouched twin
    ys, _ = agent2.net.forward_sequence(lesson.inputs, np.append(lesson.actions, 0))
    assert np.allclose(np.array(seen), ys[:-1, :, 0])


def test_forced_action_moves_the_context_as_if_chosen():
    agent = recurrent_q_agent(seed=4)
    env = CupCollectionEnv()
    obs, info = env.reset(seed=0, options={"instance": "B"})
    agent.begin_trial(obs, info, learning=False)
    agent.act(obs, info, greedy=True, force=2)
    twin = RecurrentOAON(agent.net.config, 3, np.random.default_rng(0))
    twin.load_state_dict(agent.net.state_dict())
    twin.values(np.asarray(obs, dtype=float))
    twin.advance(2)
    assert np.array_equal(agent.net.context, twin.context)


# ------------------------------------------------------------------------------------- recurrent-model

def test_model_config_checks_shapes():
    with pytest.raises(ValueError, match="n_outputs must be 5"):
        RecurrentModelConfig(model=RecurrentNetConfig(4, 8, 5, 4), q_net=NetConfig(9, 4), temperature=TEMP)
    with pytest.raises(ValueError, match="n_inputs must be 9"):
        RecurrentModelConfig(model=RecurrentNetConfig(4, 8, 5, 5), q_net=NetConfig(4, 4), temperature=TEMP)


def test_model_targets_are_next_sensation_and_scaled_payoff():
    lesson = Lesson(np.array([[1.0, 2], [3, 4], [5, 6]]), np.array([0, 1]), np.array([0.0, 1.0]), True)
    assert np.array_equal(model_targets(lesson, 0.5), [[3, 4, 0.0], [5, 6, 0.5]])


def test_recurrent_model_q_inputs_are_sensation_plus_model_context_and_replay_rebuilds_them():
    agent = model_agent(seed=5)
    agent.learn = lambda: None  # keep the weights fixed for the comparison
    env = CupCollectionEnv()
    obs, info = env.reset(seed=5)
    agent.begin_trial(obs, info, learning=True)
    used = []
    done = False
    while not done:
        a = agent.act(obs, info)
        used.append(agent._xq.copy())
        obs, r, term, trunc, info = env.step(a)
        agent.observe(a, r, obs, term, trunc, info)
        done = term or trunc
    agent.end_trial()
    lesson = agent.history[-1]
    assert agent.book.memory.lessons[-1] is lesson
    rebuilt = agent.q_lesson(lesson).inputs
    assert rebuilt.shape == (len(lesson) + 1, 9)
    assert np.allclose(rebuilt[:-1], np.array(used))
    assert np.array_equal(rebuilt[:, :4], lesson.inputs)
    assert not rebuilt[0, 4:].any()  # the context is 0 at the start of a trial (7.4)


def test_model_learns_to_predict_a_deterministic_trial():
    agent = model_agent(seed=6)
    env = CupCollectionEnv()
    env.reset(seed=6)
    for k in range(3):
        run_trial(env, agent, trial=k, learning=True)
    lesson = agent.history[0]
    targets = model_targets(lesson, 0.5)
    first = agent.model.train_sequence(lesson.inputs[:-1], lesson.actions, targets)
    for _ in range(60):
        agent.train_model()
    last = agent.model.train_sequence(lesson.inputs[:-1], lesson.actions, targets)
    assert last < 0.5 * first
    agent.freeze_model = True
    w = agent.model.w1.copy()
    agent.train_model()
    assert np.array_equal(w, agent.model.w1)


@pytest.mark.parametrize("make", [window_agent, recurrent_q_agent, model_agent])
def test_same_seed_same_learning(make):
    def trace(agent):
        env = CupCollectionEnv(random_bits=0, control_error=0.15)
        env.reset(seed=11)
        return [run_trial(env, agent, trial=k, learning=True).steps for k in range(4)] + [
            float(np.sum(v)) for v in (getattr(agent, "q", None) or agent.net).state_dict().values()]

    assert trace(make(seed=2)) == trace(make(seed=2))


def test_recurrent_model_trains_and_replays_from_lessons_checked_once():
    """The model's BPTT passes and the Q-lessons' contexts come from a lesson's arrays checked once (issue 45): the
    same weights and contexts as train_sequence and forward_sequence on the lesson itself, and a lesson replaced in
    the cache under a reused id is checked again."""
    agent = model_agent(seed=2)
    env = CupCollectionEnv()
    for k in range(3):
        run_trial(env, agent, trial=k, learning=True, seed=k)
    twin = copy.deepcopy(agent.model)
    for lesson in agent.history:
        agent.model.train_checked(*agent._arrays(lesson)[:4])
        twin.train_sequence(lesson.inputs[:-1], lesson.actions, model_targets(lesson, agent.config.payoff_scale))
        for name in ("w1", "w2", "d1", "d2"):
            np.testing.assert_array_equal(getattr(agent.model, name), getattr(twin, name))
        np.testing.assert_array_equal(agent.q_lesson(lesson).inputs[:, 4:],
                                      twin.forward_sequence(lesson.inputs, np.append(lesson.actions, 0))[1][:-1])
    lesson = agent.history[0]
    other = Lesson(lesson.inputs[::-1].copy(), lesson.actions, lesson.rewards, terminated=False)
    agent._checked[id(other)] = agent._checked[id(lesson)]  # as if the id had been reused
    np.testing.assert_array_equal(agent._arrays(other)[4], other.inputs)


def test_the_models_passes_in_one_call_are_train_sequence_on_each_pick():
    """``train_model`` trains on its picks in one compiled call over the packed history (issue 45): the same weights,
    loss and random stream as ``train_sequence`` on each picked lesson in turn, as the history grows and when it is
    replaced."""
    agent = model_agent(seed=3)
    walks = [lesson for lesson, _ in _probe_walks(1, 5, 12, 10)]  # random walks of the cup world
    twin, twin_rng = copy.deepcopy(agent.model), copy.deepcopy(agent.rng)
    for k in range(12):
        agent.history.append(walks[k])
        if k == 8:
            agent.history = agent.history[2:]  # replaced: packed anew
        n = len(agent.history)
        picks = [n - 1] + list(twin_rng.integers(0, n, agent.config.model_lessons_per_trial - 1))
        want = sum(twin.train_sequence(agent.history[i].inputs[:-1], agent.history[i].actions,
                                       model_targets(agent.history[i], agent.config.payoff_scale)) for i in picks)
        assert agent.train_model() == want / len(picks)
        for name in ("w1", "w2", "d1", "d2"):
            np.testing.assert_array_equal(getattr(agent.model, name), getattr(twin, name))
    assert agent.rng.bit_generator.state == twin_rng.bit_generator.state
    xs, actions, targets, ones, starts = agent._packed_history()
    for bad in ((xs[:, :3], actions, targets, ones, starts), (xs, actions + 3, targets, ones, starts),
                (xs, actions, targets, ones, starts[::-1].copy())):
        with pytest.raises(ValueError, match="packed lessons"):  # the kernel indexes without bounds checks
            agent.model.train_lessons(bad, [0])

