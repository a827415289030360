"""Ch. 5's compiled greedy test play is run_trial's play, step for step: the same steps, reward and outcome, the same
world and learner left behind, the same random stream; anything but the plain case plays through run_trial."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.agents.qcon import QCON
from connrl.core.rollout import run_trial
from connrl.experiments.robot import RobotParams
from connrl.tasks import robot_play
from connrl.tasks.robot import make_agent, make_env


def _run(task: str, **world):
    """A world and a QCON-T a few trials into learning (a random net's plays are dull)."""
    p = RobotParams(task=task, **world)
    env, agent = make_env(p), make_agent(p, np.random.default_rng(4))
    for k in range(4):
        run_trial(env, agent, trial=k, learning=True, seed=300 + k)
    return p, agent


@pytest.mark.parametrize(("task", "world"), [("DK", {}), ("DP", {}), ("WFL", {}), ("WFR", {}),
                                             ("DP", {"pass_depth": 12.0, "collision": "cancel"}),
                                             ("DK", {"sonar_origin": "body", "edge_mark": "both"})])
def test_the_compiled_play_is_run_trials_play(task, world):
    p, agent = _run(task, **world)
    env, ref_env = make_env(p), make_env(p)
    assert robot_play.compiled(env, agent)
    rng = np.random.default_rng(0)
    for k in range(10):
        start, seed = env.sample_task(rng), int(rng.integers(2**31))
        max_steps = p.max_steps if k % 3 else 7  # the protocol's cut, and one shorter than the world's
        ref = run_trial(ref_env, agent, trial=0, learning=False, seed=seed, options={"start": start},
                        max_steps=max_steps)
        ref_agent = (agent._x.copy(), agent.last_probabilities.copy())
        got = robot_play.greedy_play(env, agent, seed, start, max_steps)
        assert (got.steps, got.total_reward, got.terminated, got.truncated, got.info["success"]) == (
            ref.steps, ref.total_reward, ref.terminated, ref.truncated, ref.info["success"])
        np.testing.assert_array_equal(agent._x, ref_agent[0])
        np.testing.assert_array_equal(agent.last_probabilities, ref_agent[1])
        assert (env.trace, env.sim.pose, env.sim.last_action, env._steps) == (
            ref_env.trace, ref_env.sim.pose, ref_env.sim.last_action, ref_env._steps)
        for a, b in zip(env._reading, ref_env._reading, strict=True):
            np.testing.assert_array_equal(a, b)
        for a, b in ((env.sim.last_collision, ref_env.sim.last_collision), (env._feat, ref_env._feat),
                     (env._feat_true, ref_env._feat_true)):
            np.testing.assert_array_equal(a, b)
        assert env.np_random.bit_generator.state == ref_env.np_random.bit_generator.state


def test_other_learners_and_worlds_play_through_run_trial():
    p, agent = _run("DK")
    env = make_env(p)
    assert robot_play.compiled(env, agent)
    assert not robot_play.compiled(env, object())
    plain = QCON(agent.config, 6, np.random.default_rng(0), q=agent.q)
    plain.planner = object()  # relaxation planning acts in Python
    assert not robot_play.compiled(env, plain)
    env.render_mode = "rgb_array"
    assert not robot_play.compiled(env, agent)
