"""Ch. 5's compiled training trial is run_trial's trial, step for step: the same steps, reward and outcome, the same
nets, lessons, stuck detector, world and learner left behind, the same two random streams, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.core.rollout import run_trial
from connrl.experiments.robot import RobotParams
from connrl.tasks.robot import make_agent, make_env
from connrl.tasks.robot_train import compiled_learning, learning_play
from tests.tasks.test_robot_play import assert_same_worlds


def _assert_same_agents(agent, ref):
    for name in ("w1", "w2", "d1", "d2"):
        np.testing.assert_array_equal(getattr(agent.q, name), getattr(ref.q, name))
    assert agent.rng.bit_generator.state == ref.rng.bit_generator.state
    np.testing.assert_array_equal(agent._x, ref._x)
    np.testing.assert_array_equal(agent.last_probabilities, ref.last_probabilities)
    d, ref_d = agent.explore.detector, ref.explore.detector
    assert len(d._pos) == len(ref_d._pos)
    for a, b in zip(d._pos, ref_d._pos, strict=True):
        np.testing.assert_array_equal(a, b)
    assert_same_lessons(agent, ref)


def assert_same_lessons(agent, ref, meta=()):
    """The same lessons stored, array for array and dtype for dtype (with the ``meta`` entries named)."""
    assert len(agent.book.memory) == len(ref.book.memory)
    for a, b in zip(agent.book.memory.lessons, ref.book.memory.lessons, strict=True):
        pairs = [(a.inputs, b.inputs), (a.actions, b.actions), (a.rewards, b.rewards)]
        for got, want in pairs + [(a.meta[k], b.meta[k]) for k in meta]:
            assert got.dtype == want.dtype
            np.testing.assert_array_equal(got, want)
        assert (a.terminated, a.truncated) == (b.terminated, b.truncated)


@pytest.mark.parametrize(("task", "world"), [("DK", {}), ("DP", {"lessons": 3}), ("WFL", {}),
                                             ("DP", {"pass_depth": 12.0, "collision": "cancel", "stuck_radius": 40.0}),
                                             ("DP", {"hidden_fraction": 0.0, "linear_output": True,
                                                     "binary_low": 0.0, "online": False})])
def test_the_compiled_training_trial_is_run_trials_trial(task, world):
    p = RobotParams(task=task, **world)
    pairs = [(make_env(p), make_agent(p, np.random.default_rng(4))) for _ in range(2)]
    (env, agent), (ref_env, ref) = pairs
    assert compiled_learning(env, agent, 0)
    boosted = 0
    for k in range(6):
        got = learning_play(env, agent, trial=k, seed=300 + k)
        want = run_trial(ref_env, ref, trial=k, learning=True, seed=300 + k)
        assert (got.steps, got.total_reward, got.terminated, got.truncated, got.info) == (
            want.steps, want.total_reward, want.terminated, want.truncated, want.info)
        assert_same_worlds(env, ref_env)
        _assert_same_agents(agent, ref)
        boosted += len(ref.explore.detector._pos) == ref.explore.detector.config.window
    assert boosted  # the detector's window filled


def test_a_watched_trial_plays_through_run_trial():
    p = RobotParams(task="DP")
    env, agent = make_env(p), make_agent(p, np.random.default_rng(4))
    seen = []
    stats = learning_play(env, agent, trial=0, seed=1, on_step=seen.append)
    assert len(seen) == stats.steps
    agent.act = agent.act  # a method replaced on the instance: the loop would not call it
    assert not compiled_learning(env, agent, 1)
    del agent.act
    assert compiled_learning(env, agent, 1)
    for part, name in ((agent.q, "update"), (agent.explore, "temperature"), (agent.explore.detector, "factor"),
                       (agent.book.recorder, "add")):
        setattr(part, name, getattr(part, name))  # ... or on one of its parts
        assert not compiled_learning(env, agent, 1)
        delattr(part, name)
