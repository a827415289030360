"""Chs. 6 and 8's compiled greedy test play over behaviours is run_trial's play, step for step: the same steps,
reward, outcome and collisions, the same world and learner left behind, the same random stream; and anything
but the plain case plays through run_trial."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from connrl.core.rollout import run_trial
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, ROOMS, sample_in_room
from connrl.experiments.recharge import RechargeParams, _test
from connrl.experiments.recharge_flat import FlatParams
from connrl.tasks import recharge_play
from connrl.tasks.recharge import BehaviourEnv, _shipped_library, make_flat_agent, make_flat_env, make_high_level_agent


def _agent(n_inputs: int, xy: bool, prefer: int | None = None):
    """A high-level learner a few trials into learning, so its choices vary (a random net's are dull); with
    ``prefer``, that behaviour's net is biased up, so it is chosen wherever it applies."""
    agent = make_high_level_agent(RechargeParams(), np.random.default_rng(3), n_inputs=n_inputs)
    env = BehaviourEnv(_shipped_library(), max_steps=60, xy=xy)
    for k in range(3):
        run_trial(env, agent, trial=k, learning=True, seed=200 + k)
    if prefer is not None:
        agent.q.w2[prefer, -1] += 5.0
    return agent


def assert_same_worlds(env, ref_env):
    """The world left as ``run_trial`` leaves it: trace, pose, last action and collision, step count, each
    behaviour's observation, the world's generator."""
    w, ref_w = env.world, ref_env.world
    assert (w.trace, w.sim.pose, w.sim.last_action, w._steps) == (
        ref_w.trace, ref_w.sim.pose, ref_w.sim.last_action, ref_w._steps)
    np.testing.assert_array_equal(w.sim.last_collision, ref_w.sim.last_collision)
    assert env._task_obs.keys() == ref_env._task_obs.keys()
    for task, obs in ref_env._task_obs.items():
        np.testing.assert_array_equal(env._task_obs[task], obs)
        assert env._task_obs[task].dtype == obs.dtype
    assert w.np_random.bit_generator.state == ref_w.np_random.bit_generator.state


def _starts(env, rng, n):
    """``n`` test tasks: random starts in each room, and two facing the charger from near it (plays that dock)."""
    layout = env.world.layout
    (x0, y0, x1, y1), (ax, ay) = layout.charger, layout.charger_approach
    heading = math.degrees(math.atan2(-ay, -ax)) % 360.0
    near = [((x0 + x1) / 2 + ax * d, (y0 + y1) / 2 + ay * d, heading) for d in (35.0, 60.0)]
    return near + [sample_in_room(rng, layout, ROOMS[k % 3]) for k in range(n - 2)]


@pytest.mark.parametrize(("world", "prefer"), [({}, None), ({}, 1), ({}, 3), ({"xy": False}, None),
                                               ({"step_scale": 0.2, "max_steps": 150, "success_reward": 500.0,
                                                 "xy_scale": 8.0}, None)])
def test_the_compiled_play_is_run_trials_play(world, prefer):
    world = {"max_steps": 120, **world}
    agent = _agent(16 if world.get("xy", True) else 14, world.get("xy", True), prefer)
    env, ref_env = BehaviourEnv(_shipped_library(), **world), BehaviourEnv(_shipped_library(), **world)
    assert recharge_play.compiled(env, agent)
    rng, collided, chosen, ended = np.random.default_rng(0), 0, set(), set()
    for start in _starts(env, rng, 10):
        seed, hits = int(rng.integers(2**31)), []
        got, got_hits = recharge_play.greedy_play(env, agent, seed, start)
        got_agent = (agent._x.copy(), agent.last_q.copy(), agent.last_probabilities.copy())
        agent._x = agent.last_q = agent.last_probabilities = None
        ref = run_trial(ref_env, agent, trial=0, learning=False, seed=seed, options={"start": start},
                        on_step=lambda info, hits=hits: (hits.append(info["collision"]), chosen.add(info["behaviour"])))
        assert (got.steps, got.total_reward, got.terminated, got.truncated, got.info["success"], got_hits) == (
            ref.steps, ref.total_reward, ref.terminated, ref.truncated, ref.info["success"], sum(hits))
        for value, ref_value in zip(got_agent, (agent._x, agent.last_q, agent.last_probabilities), strict=True):
            np.testing.assert_array_equal(value, ref_value)
        assert_same_worlds(env, ref_env)
        collided += got_hits
        ended.add(got.terminated)
    assert collided > 0 and (prefer is not None or ended == {True, False})  # contacts, dockings, time-outs
    if prefer is None:
        assert "DK" in chosen and chosen & {"WFL", "WFR"}
    else:
        assert BEHAVIOUR_TASKS[prefer] in chosen


def test_the_protocols_tests_are_the_same_compiled_or_not(monkeypatch):
    """Ch. 6's ``_test`` gives the same totals, steps, dockings and collisions per room either way."""
    agent = _agent(16, True)
    env = BehaviourEnv(_shipped_library(), max_steps=120)
    rng = np.random.default_rng(1)
    starts = _starts(env, rng, 6)
    tasks, seeds = [(ROOMS[k % 3], s) for k, s in enumerate(starts)], rng.integers(2**31, size=len(starts))
    fast = _test(env, agent, tasks, seeds)
    monkeypatch.setattr(recharge_play, "compiled", lambda env, agent: False)
    assert _test(env, agent, tasks, seeds) == fast


def test_other_learners_and_worlds_play_through_run_trial(monkeypatch):
    agent = _agent(16, True)
    assert not recharge_play.compiled(BehaviourEnv(_shipped_library(), obs="high").world, agent)  # primitives
    from connrl.tasks.recharge_together import TrainingBehaviourEnv
    assert not recharge_play.compiled(TrainingBehaviourEnv.__new__(TrainingBehaviourEnv), agent)
    env = BehaviourEnv(_shipped_library())
    assert recharge_play.compiled(env, agent)
    assert not recharge_play.compiled(env, object())
    assert not recharge_play.compiled(BehaviourEnv(_shipped_library(), xy=False), agent)  # 16 inputs on a 14-unit world
    monkeypatch.setattr(recharge_play, "hypot_matches", lambda: False)  # an interpreter whose hypot is not the port's
    assert not recharge_play.compiled(env, agent)


@pytest.mark.parametrize("collision_penalty", [0.0, -5.0])
def test_the_compiled_flat_play_is_run_trials_play(collision_penalty):
    """Exp. 1's plays (QCON over primitives on the flat input) too: stats, collisions, trace, pose, stream."""
    p = dataclasses.replace(FlatParams(), collision_penalty=collision_penalty)
    agent = make_flat_agent(p, np.random.default_rng(5))
    train = make_flat_env(p)
    for k in range(3):
        run_trial(train, agent, trial=k, learning=True, seed=400 + k)
    env, ref_env = make_flat_env(p), make_flat_env(p)
    assert recharge_play.compiled_flat(env, agent) and not recharge_play.compiled(env, agent)
    rng, collided, ended = np.random.default_rng(2), 0, set()
    for start in _starts(BehaviourEnv(_shipped_library()), rng, 8):
        seed, hits = int(rng.integers(2**31)), []
        got, got_hits = recharge_play.greedy_play_flat(env, agent, seed, start)
        got_agent = (agent._x.copy(), agent.last_probabilities.copy())
        agent._x = agent.last_probabilities = None
        ref = run_trial(ref_env, agent, trial=0, learning=False, seed=seed, options={"start": start},
                        on_step=lambda info, hits=hits: hits.append(info["collision"]))
        assert (got.steps, got.total_reward, got.terminated, got.truncated, got.info["success"], got_hits) == (
            ref.steps, ref.total_reward, ref.terminated, ref.truncated, ref.info["success"], sum(hits))
        np.testing.assert_array_equal(got_agent[0], agent._x)
        np.testing.assert_array_equal(got_agent[1], agent.last_probabilities)
        assert (env.trace, env.sim.pose, env.sim.last_action, env._steps) == (
            ref_env.trace, ref_env.sim.pose, ref_env.sim.last_action, ref_env._steps)
        np.testing.assert_array_equal(env.sim.last_collision, ref_env.sim.last_collision)
        assert env.np_random.bit_generator.state == ref_env.np_random.bit_generator.state
        collided += got_hits
        ended.add(got.terminated)
    assert collided > 0 and False in ended
