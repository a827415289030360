"""QCON-T of Ch. 5: the lesson-replay kernel equals the reference replay, the 5.4.3 repairs, the agent."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.agents.teaching import TeachingConfig, TeachingQCON
from connrl.core.exploration import boltzmann_probabilities
from connrl.core.lessons import Lesson
from connrl.core.replay import REPAIRS, ReplayParams, repair_step, replay_q, replay_q_reference
from connrl.core.replay_kernel import replay_oaon
from connrl.experiments.robot import ROBOT_PARAMS, binary_columns, make_agent, taught_lessons
from connrl.nets import OAON, NetConfig


def _lesson(rng, n=12, d=7, terminated=True):
    return Lesson(rng.uniform(-0.5, 1.0, (n + 1, d)), rng.integers(0, 4, n), rng.choice([0.0, -10.0, 100.0], n),
                  terminated=terminated, truncated=not terminated)


def _pair(hidden, d=7, n_actions=4):
    cfg = NetConfig(d, hidden, value_range=100.0, init_range=0.5, lr=0.05, momentum=0.9 if hidden else 0.0)
    return OAON(cfg, n_actions, np.random.default_rng(3)), OAON(cfg, n_actions, np.random.default_rng(3))


@pytest.mark.parametrize("hidden", [5, 0])
@pytest.mark.parametrize("terminated", [True, False])
@pytest.mark.parametrize("p_threshold", [0.0, 0.2])
def test_kernel_equals_reference_replay(hidden, terminated, p_threshold):
    rng = np.random.default_rng(0)
    lesson = _lesson(rng, terminated=terminated)
    fast, ref = _pair(hidden)
    params = ReplayParams(gamma=0.9, lam=0.7, temperature=10.0, p_threshold=p_threshold, clip=None)
    assert replay_oaon(fast, lesson, params) == replay_q_reference(ref, lesson, params)  # the plain loop
    np.testing.assert_allclose(fast.w2, ref.w2, atol=1e-12)
    np.testing.assert_allclose(fast.w1, ref.w1, atol=1e-12)


@pytest.mark.parametrize("repair", ["lower", "raise"])
def test_kernel_repairs_equal_reference(repair):
    rng = np.random.default_rng(1)
    lesson = _lesson(rng)
    fast, ref = _pair(5)
    params = ReplayParams(gamma=0.9, lam=0.7)
    assert replay_oaon(fast, lesson, params, REPAIRS.index(repair)) == replay_q_reference(ref, lesson, params, repair)
    np.testing.assert_allclose(fast.w1, ref.w1, atol=1e-12)
    np.testing.assert_allclose(fast.w2, ref.w2, atol=1e-12)


def test_kernel_first_update_target_is_td_lambda_return():
    # one-step terminated lesson: target = r; the update moves Q(x0, a0) toward r exactly as OAON.update does
    x = np.array([[0.3, -0.2], [0.1, 0.4]])
    lesson = Lesson(x, np.array([1]), np.array([100.0]), terminated=True)
    fast, ref = _pair(3, d=2, n_actions=2)
    replay_oaon(fast, lesson, ReplayParams(gamma=0.9, lam=0.7))
    ref.update(x[0], 1, 100.0)
    np.testing.assert_array_equal(fast.w2, ref.w2)


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


def test_temperature_is_applied_to_q_over_merit_scale():
    p = {**ROBOT_PARAMS, "lessons": 0}
    agent = make_agent(p, np.random.default_rng(0))
    obs = np.random.default_rng(1).uniform(-0.25, 1.0, 52)
    agent.begin_trial(obs, {"pose": (100.0, 100.0, 0.0)}, trial=0, learning=True)
    agent.act(obs, {"pose": (100.0, 100.0, 0.0)})
    q = agent.q.values(obs)
    np.testing.assert_allclose(agent.last_probabilities, boltzmann_probabilities(q / 100.0, 0.05))


def test_learn_replays_at_most_the_lessons_available():
    p = {**ROBOT_PARAMS, "lessons": 0}
    agent = make_agent(p, np.random.default_rng(0))
    seen = []
    agent.replay_lesson = lambda lesson, pt: seen.append(pt)
    agent.learning, agent.trial = True, 0
    agent.learn()
    assert seen == []
    agent.book.memory.add(_lesson(np.random.default_rng(0), d=52))
    agent.learn()
    assert seen == [0.02]  # one lesson in memory: replayed once, not 60 times (5.3.5 fn. 1)


def test_taught_lessons_shipped_and_reencoded():
    dp = taught_lessons("DP", 10)
    assert len(dp) == 10 and all(lesson.taught and lesson.terminated for lesson in dp)
    assert all(lesson.rewards[-1] == 100.0 for lesson in dp)  # positive examples (5.4.1)
    assert len(taught_lessons("DK", 3)) == 3 and len(taught_lessons("WFL", 5)) == 5
    cols = binary_columns("DP")
    assert set(np.unique(dp[0].inputs[:, cols])) <= {-0.5, 0.5}
    zero_one = taught_lessons("DP", 1, binary_low=0.0)[0]
    assert set(np.unique(zero_one.inputs[:, cols])) <= {0.0, 1.0}
    np.testing.assert_array_equal(zero_one.inputs[:, :24], dp[0].inputs[:, :24])  # sonar untouched
    wf = taught_lessons("WFL", 1, binary_low=0.0)[0]
    np.testing.assert_array_equal(wf.inputs[:, 28:30], taught_lessons("WFL", 1)[0].inputs[:, 28:30])
    with pytest.raises(ValueError, match="taught lessons asked for"):
        taught_lessons("WFL", 6)


def test_agent_config_matches_thesis():
    agent = make_agent({**ROBOT_PARAMS, "task": "DP", "lessons": 3}, np.random.default_rng(0))
    c = agent.config
    assert (c.net.n_inputs, c.net.n_hidden, c.net.lr, c.net.momentum, c.net.init_range) == (52, 16, 0.05, 0.9, 0.5)
    assert c.net.value_range == 100.0 and c.gamma == 0.9 and c.lam == 0.7
    assert c.temperature(0) == pytest.approx(0.05) and c.temperature(299) == pytest.approx(0.02)
    assert len(agent.book.taught) == 3
    wf = make_agent({**ROBOT_PARAMS, "task": "WFL", "lessons": 0, "hidden_fraction": 0.0}, np.random.default_rng(0))
    assert wf.config.net.n_hidden == 0 and wf.config.net.n_inputs == 36
    with pytest.raises(ValueError, match="repair must be one of"):
        TeachingConfig(repair="up")
    assert isinstance(agent, TeachingQCON)


def test_taught_lessons_replayed_with_p_zero_and_q_scale_temperature():
    """5.3.5 / 3.7: every taught lesson is replayed after each trial with P_t = 0 (no taught action is
    skipped as non-policy), experienced ones with P_l = 2 %; the kernel's T is on the scale of Q (x 100)."""
    agent = make_agent({**ROBOT_PARAMS, "task": "DP", "lessons": 3}, np.random.default_rng(0))
    seen = []
    agent.replay_lesson = lambda lesson, pt: seen.append((lesson.taught, pt))
    agent.learning, agent.trial = True, 0
    agent.book.memory.add(_lesson(np.random.default_rng(0), d=52))
    agent.learn()
    assert seen == [(False, 0.02), (True, 0.0), (True, 0.0), (True, 0.0)]
    params = TeachingQCON.replay_params(agent, 0.0)
    assert params.temperature == pytest.approx(0.05 * 100.0) and params.p_threshold == 0.0
    # with P_t = 0 the kernel updates every experience of a taught lesson, however unlikely its action
    lesson = agent.book.taught[0]
    used = replay_oaon(agent.q, lesson, params)
    assert used == len(lesson)
