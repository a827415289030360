"""QCON-T (5.3, 3.7): temperature on Q / merit scale, how many lessons are replayed, taught lessons with P_t = 0."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.agents.teaching import TeachingQCON
from connrl.core.exploration import boltzmann_probabilities
from connrl.core.lessons import Lesson
from connrl.core.replay_kernel import replay_oaon
from connrl.experiments.robot import RobotParams
from connrl.tasks.robot import make_agent


def _lesson(rng, n=12, d=7, terminated=True):
    return Lesson(rng.uniform(-0.5, 1.0, (n + 1, d)), rng.integers(0, 4, n), rng.choice([0.0, -10.0, 100.0], n),
                  terminated=terminated, truncated=not terminated)


def test_temperature_is_applied_to_q_over_merit_scale():
    agent = make_agent(RobotParams(lessons=0), np.random.default_rng(0))
    obs = np.random.default_rng(1).uniform(-0.25, 1.0, 52)
    agent.begin_trial(obs, {"pose": (100.0, 100.0, 0.0)}, trial=0, learning=True)
    agent.act(obs, {"pose": (100.0, 100.0, 0.0)})
    q = agent.q.values(obs)
    np.testing.assert_allclose(agent.last_probabilities, boltzmann_probabilities(q / 100.0, 0.05))


def test_learn_replays_at_most_the_lessons_available():
    agent = make_agent(RobotParams(lessons=0), np.random.default_rng(0))
    seen = []
    agent.replay_lesson = lambda lesson, pt: seen.append(pt)
    agent.learning, agent.trial = True, 0
    agent.learn()
    assert seen == []
    agent.book.memory.add(_lesson(np.random.default_rng(0), d=52))
    agent.learn()
    assert seen == [0.02]  # one lesson in memory: replayed once, not 60 times (5.3.5 fn. 1)


def test_taught_lessons_replayed_with_p_zero_and_q_scale_temperature():
    """5.3.5 / 3.7: every taught lesson is replayed after each trial with P_t = 0 (no taught action is
    skipped as non-policy), experienced ones with P_l = 2 %; the kernel's T is on the scale of Q (x 100)."""
    agent = make_agent(RobotParams(task="DP", lessons=3), np.random.default_rng(0))
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
