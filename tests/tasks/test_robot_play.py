"""Ch. 5's compiled greedy test play is run_trial's play, step for step: the same steps, reward and outcome, the same
world and learner left behind, the same random stream; anything but the plain case plays through run_trial."""

from __future__ import annotations

import math

import numpy as np
import pytest

from connrl.agents.qcon import QCON
from connrl.core.rollout import run_trial
from connrl.experiments.robot import RobotParams
from connrl.tasks import robot_play
from connrl.tasks.robot import evaluate, make_agent, make_env


def _run(task: str, **world):
    """A world and a QCON-T a few trials into learning (a random net's plays are dull)."""
    p = RobotParams(task=task, **world)
    env, agent = make_env(p), make_agent(p, np.random.default_rng(4))
    for k in range(4):
        run_trial(env, agent, trial=k, learning=True, seed=300 + k)
    return p, agent


def assert_same_worlds(env, ref_env):
    """The world and simulator two plays leave: trace, pose, last action, steps, reading, features, generator."""
    assert (env.trace, env.sim.pose, env.sim.last_action, env._steps) == (
        ref_env.trace, ref_env.sim.pose, ref_env.sim.last_action, ref_env._steps)
    for a, b in zip(env._reading, ref_env._reading, strict=True):
        np.testing.assert_array_equal(a, b)
    for a, b in ((env.sim.last_collision, ref_env.sim.last_collision), (env._feat, ref_env._feat),
                 (env._feat_true, ref_env._feat_true)):
        np.testing.assert_array_equal(a, b)
    assert env.np_random.bit_generator.state == ref_env.np_random.bit_generator.state


def _starts(env, rng, n):
    """``n`` test tasks from the task's own starts; for DK two of them face the charger from near it (plays that
    dock)."""
    starts = [env.sample_task(rng) for _ in range(n)]
    if env.task == "DK":
        (x0, y0, x1, y1), (ax, ay) = env.layout.charger, env.layout.charger_approach
        heading = math.degrees(math.atan2(-ay, -ax)) % 360.0
        starts[:2] = [((x0 + x1) / 2 + ax * d, (y0 + y1) / 2 + ay * d, heading) for d in (35.0, 50.0)]
    return starts


@pytest.mark.parametrize(("task", "world"), [("DK", {}), ("DP", {}), ("WFL", {}), ("WFR", {}),
                                             ("DP", {"pass_depth": 12.0, "collision": "cancel"}),
                                             ("DK", {"sonar_origin": "body", "edge_mark": "both"}),
                                             ("DP", {"hidden_fraction": 0.0, "linear_output": True,
                                                     "binary_low": 0.0})])
def test_the_compiled_play_is_run_trials_play(task, world):
    p, agent = _run(task, **world)
    env, ref_env = make_env(p), make_env(p)
    assert robot_play.compiled(env, agent)
    rng, ended, collisions = np.random.default_rng(0), set(), set()
    for k, start in enumerate(_starts(env, rng, 12)):
        seed = int(rng.integers(2**31))
        max_steps = p.max_steps if k % 3 else 7  # the protocol's cut, and one shorter than the world's
        got = robot_play.greedy_play(env, agent, seed, start, max_steps)
        got_agent = (agent._x.copy(), agent.last_probabilities.copy())
        agent._x = agent.last_probabilities = None
        ref = run_trial(ref_env, agent, trial=0, learning=False, seed=seed, options={"start": start},
                        max_steps=max_steps, on_step=lambda info: collisions.add(info["collision"]))
        assert (got.steps, got.total_reward, got.terminated, got.truncated, got.info["success"]) == (
            ref.steps, ref.total_reward, ref.terminated, ref.truncated, ref.info["success"])
        np.testing.assert_array_equal(got_agent[0], agent._x)
        np.testing.assert_array_equal(got_agent[1], agent.last_probabilities)
        assert_same_worlds(env, ref_env)
        ended.add(got.terminated)
    assert True in collisions  # contacts were played
    if task == "DK":
        assert ended == {True, False}  # dockings and time-outs


def test_evaluate_is_the_same_compiled_or_not(monkeypatch):
    """Ch. 5's ``evaluate`` gives the same score and recorded paths either way."""
    p, agent = _run("DP")
    env, rng = make_env(p), np.random.default_rng(1)
    tasks, seeds = _starts(env, rng, 8), rng.integers(2**31, size=8)
    paths = [None] * 3
    fast = evaluate(env, agent, tasks, seeds, p.max_steps, paths)
    monkeypatch.setattr(robot_play, "compiled", lambda env, agent: False)
    slow_paths = [None] * 3
    assert evaluate(env, agent, tasks, seeds, p.max_steps, slow_paths) == fast and slow_paths == paths


def test_other_learners_and_worlds_play_through_run_trial(monkeypatch):
    p, agent = _run("DK")
    env = make_env(p)
    assert robot_play.compiled(env, agent)
    assert not robot_play.compiled(env, object())
    plain = QCON(agent.config, 6, np.random.default_rng(0), q=agent.q)
    plain.planner = object()  # relaxation planning acts in Python
    assert not robot_play.compiled(env, plain)
    assert not robot_play.compiled(make_env(RobotParams(task="WFL")), agent)  # a DK learner on 36 inputs
    monkeypatch.setattr(robot_play, "hypot_matches", lambda: False)  # an interpreter whose hypot is not the port's
    assert not robot_play.compiled(env, agent)
    monkeypatch.undo()
    env.render_mode = "rgb_array"
    assert not robot_play.compiled(env, agent)
