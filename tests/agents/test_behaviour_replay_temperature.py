"""Ch. 6's behaviour-level learner acts with Eq. 6.6 at temperature T x merit_scale (its Q-values are in +-100, the
temperatures of 6.6 are for merits scaled to about +-1: exp(Q / (T merit_scale)) = exp((Q / merit_scale) / T)). Its
replay must use the same temperature: the non-policy test (3.5.1, 6.6) drops a step whose action had probability
below P_l *under the acting policy*, so it must recompute the probabilities the choice was made with. Forgetting
merit_scale there (T alone: merit_scale, by default 100, times colder) would make nearly every non-greedy choice
look non-policy."""

import sys

import numpy as np
import pytest

import connrl.core.replay as core_replay
from connrl.agents import LinearSchedule, QCONConfig, ReplayConfig
from connrl.agents.behaviour_level import BehaviourQCON, BehaviourRecurrentQ
from connrl.agents.memory import RecurrentQConfig, replay_recurrent_q, replay_recurrent_q_lessons
from connrl.core.exploration import TemperatureSchedule
from connrl.nets import NetConfig
from connrl.nets.recurrent import RecurrentNetConfig

T, MERIT_SCALE = 0.05, 40.0


def capture(monkeypatch, *originals):
    """Replace the replay functions ``originals`` (one lesson, or a trial's lessons in one call) wherever a connrl
    module holds them (so a move of the caller keeps the test meaningful); returns the list of the ReplayParams they
    are called with."""
    seen = []

    def fake(*args, **kw):
        seen.extend(a for a in args if isinstance(a, core_replay.ReplayParams))
        return 0

    for original in originals:
        for name, module in list(sys.modules.items()):
            if name.startswith("connrl") and getattr(module, original.__name__, None) is original:
                monkeypatch.setattr(module, original.__name__, fake)
    return seen


def test_behaviour_replay_uses_the_acting_temperature_times_merit_scale(monkeypatch):
    cfg = QCONConfig(net=NetConfig(3, 4, value_range=100.0, init_range=0.5, lr=0.05),
                     temperature=TemperatureSchedule.direct(T, T, 10), gamma=0.99,
                     replay=ReplayConfig(capacity=10, lessons_per_trial=LinearSchedule(1, 1), p_threshold=0.01))
    agent = BehaviourQCON(cfg, 4, np.random.default_rng(0), merit_scale=MERIT_SCALE)
    x, app = np.array([0.3, -0.2, 0.1]), {"applicable": np.array([True, True, False, True])}
    agent.begin_trial(x, app, trial=0, learning=True)
    q = agent.q.values(x)
    agent.act(x, app)
    acting_p = agent.last_probabilities
    agent.observe(0, 0.0, x, True, False, app)
    agent.end_trial()
    seen = capture(monkeypatch, core_replay.replay_q, core_replay.replay_q_lessons)
    agent.learn()
    assert len(seen) == 1
    assert seen[0].temperature == pytest.approx(T * MERIT_SCALE)
    # the replay's probabilities (Eq. 6.6 at its temperature, with the step's W) are the ones the choice had
    assert_same_choice_probabilities(q, seen[0].temperature, acting_p)


def assert_same_choice_probabilities(q, temperature, acting_p):
    """Eq. 6.6 written out with the step's W (behaviour 2 inapplicable) at the replay's temperature."""
    w = np.array([1.0, 1.0, 0.0, 1.0])
    e = w * np.exp((q - q.max()) / temperature)
    np.testing.assert_allclose(e / e.sum(), acting_p, rtol=1e-9)


def test_recurrent_behaviour_replay_uses_the_acting_temperature_times_merit_scale(monkeypatch):
    """The same for Ch. 8's recurrent learner over behaviours (8.3), whose replay is batch BPTT."""
    cfg = RecurrentQConfig(net=RecurrentNetConfig(3, 5, 2, value_range=100.0, init_range=0.5, lr=0.08),
                           temperature=TemperatureSchedule.direct(T, T, 10), gamma=0.99,
                           replay=ReplayConfig(capacity=10, lessons_per_trial=LinearSchedule(1, 1), p_threshold=0.01,
                                               batch=True))
    agent = BehaviourRecurrentQ(cfg, 4, np.random.default_rng(0), merit_scale=MERIT_SCALE)
    x, app = np.array([0.3, -0.2, 0.1]), {"applicable": np.array([True, True, False, True])}
    agent.begin_trial(x, app, trial=0, learning=True)
    agent.act(x, app)
    q, acting_p = agent.last_q, agent.last_probabilities
    agent.observe(0, 0.0, x, True, False, app)
    agent.end_trial()
    seen = capture(monkeypatch, replay_recurrent_q, replay_recurrent_q_lessons)
    agent.learn()
    assert len(seen) == 1
    assert seen[0].temperature == pytest.approx(T * MERIT_SCALE)
    assert_same_choice_probabilities(q, seen[0].temperature, acting_p)
