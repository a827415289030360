"""What every lesson agent shares: lessons filed and replayed, taught lessons, configs, any Gymnasium task."""

import gymnasium as gym
import numpy as np
import pytest

from connrl.agents import AHCON, QCON, AHCONConfig, LinearSchedule, QCONConfig, ReplayConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.core.lessons import Lesson
from connrl.core.rollout import run_trial
from connrl.nets import NetConfig

TEMP = TemperatureSchedule.inverse(10, 30, 50)


def qcon(n_inputs=4, n_actions=2, replay=None, seed=0, **kw):
    cfg = QCONConfig(net=NetConfig(n_inputs, 5, lr=0.2, init_range=0.5), temperature=TEMP, replay=replay, **kw)
    return QCON(cfg, n_actions, np.random.default_rng(seed))


def test_lessons_are_filed_only_for_learning_trials_and_replayed():
    env = gym.make("CartPole-v1")
    replay = ReplayConfig(capacity=3, lessons_per_trial=LinearSchedule(2, 2), p_threshold=0.0)
    agent = qcon(replay=replay)
    calls = []
    agent.replay_lesson = lambda lesson, p: calls.append((len(lesson), p))
    for k in range(4):
        run_trial(env, agent, trial=k, learning=True, seed=k)
    assert len(agent.book.memory) == 3 and len(calls) == 8
    run_trial(env, agent, trial=4, learning=False, seed=9)
    assert len(agent.book.memory) == 3 and len(calls) == 8


def test_taught_lessons_are_replayed_with_their_threshold():
    replay = ReplayConfig(capacity=5, lessons_per_trial=LinearSchedule(0, 0), taught_p_threshold=0.0)
    agent = qcon(replay=replay)
    calls = []
    agent.replay_lesson = lambda lesson, p: calls.append((lesson.taught, p))
    agent.add_taught_lessons([Lesson(np.zeros((2, 4)), [1], [1.0], terminated=True)])
    agent.begin_trial(np.zeros(4))
    agent.learn()
    assert calls == [(True, 0.0)]


@pytest.mark.parametrize("kind", ["qcon", "ahcon"])
def test_works_on_gymnasium_cartpole_and_is_deterministic(kind):
    def run(seed):
        env = gym.make("CartPole-v1")
        net = NetConfig(4, 6, lr=0.1, init_range=0.5)
        replay = ReplayConfig(capacity=20, lessons_per_trial=LinearSchedule(3, 3), p_threshold=0.01)
        if kind == "qcon":
            agent = QCON(QCONConfig(net=net, temperature=TEMP, lam=0.7, replay=replay), 2, np.random.default_rng(seed))
        else:
            agent = AHCON(AHCONConfig(v_net=net, policy_net=net, temperature=TEMP, replay=replay), 2,
                          np.random.default_rng(seed))
        return [run_trial(env, agent, trial=k, learning=True, seed=seed * 100 + k).steps for k in range(8)]

    a, b = run(3), run(3)
    assert a == b and all(s > 0 for s in a)


def test_bad_config_is_rejected():
    with pytest.raises(ValueError, match="gamma"):
        QCONConfig(net=NetConfig(2), temperature=TEMP, gamma=1.5)
    with pytest.raises(ValueError, match="lam"):
        QCONConfig(net=NetConfig(2), temperature=TEMP, lam=-0.1)
    with pytest.raises(ValueError, match="p_threshold"):
        ReplayConfig(p_threshold=1.5)
    with pytest.raises(ValueError, match="capacity"):
        ReplayConfig(capacity=0)


def test_p_threshold_moves_with_lesson_age():
    r = ReplayConfig(capacity=70, p_threshold=1e-4, p_threshold_oldest=1e-7)
    assert r.threshold_for_age(0) == pytest.approx(1e-4)
    assert r.threshold_for_age(69) == pytest.approx(1e-7)
    assert 1e-7 < r.threshold_for_age(35) < 1e-4


@pytest.mark.parametrize("order", ["after", "shuffled"])
def test_taught_lessons_replayed_after_or_shuffled_among_the_experienced(order):
    """Every chosen lesson is replayed once per trial either way; "after" puts the taught ones last (as before
    taught_order existed), "shuffled" puts them at random places (5.3.5 gives no order)."""
    replay = ReplayConfig(capacity=50, lessons_per_trial=LinearSchedule(12, 12), p_threshold=0.0, taught_order=order)
    agent = qcon(replay=replay, seed=4)
    taught = [Lesson(np.full((2, 4), k), [0], [1.0], terminated=True, taught=True) for k in range(4)]
    agent.add_taught_lessons(taught)
    for k in range(20):  # 20 experienced lessons in memory
        agent.book.memory.add(Lesson(np.full((2, 4), 100 + k), [1], [0.0], terminated=True))
    calls = []
    agent.replay_lesson = lambda lesson, p: calls.append(lesson.taught)
    agent.begin_trial(np.zeros(4), trial=0)
    agent.learn()
    assert len(calls) == 16 and sum(calls) == 4
    if order == "after":
        assert calls == [False] * 12 + [True] * 4
    else:  # over seeds, a taught lesson takes every place, first and last included, not only the last four
        places = set()
        for seed in range(30):
            agent.rng = np.random.default_rng(seed)
            calls.clear()
            agent.learn()
            places.update(i for i, taught in enumerate(calls) if taught)
        assert places == set(range(16))
    with pytest.raises(ValueError, match="taught_order must be one of after, shuffled"):
        ReplayConfig(taught_order="first")


def test_p_threshold_moves_linearly_from_zero_for_the_latest_lesson():
    """6.6: P_l "between 0 and 0.02, depending on the recency" (0 for the latest): linear, as log-linear cannot
    start at 0."""
    r = ReplayConfig(capacity=101, p_threshold=0.0, p_threshold_oldest=0.02)
    assert [r.threshold_for_age(a) for a in (0, 50, 100, 150)] == [0.0, 0.01, 0.02, 0.02]
