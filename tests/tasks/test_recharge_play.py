"""Chs. 6 and 8's compiled greedy test play over behaviours is run_trial's play, step for step: the same steps,
reward, outcome and collisions, the same world and learner left behind, the same random stream; and anything
but the plain case plays through run_trial."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.core.rollout import run_trial
from connrl.envs.robot.recharge import ROOMS, sample_in_room
from connrl.experiments.recharge import RechargeParams
from connrl.tasks import recharge_play
from connrl.tasks.recharge import BehaviourEnv, _shipped_library, make_high_level_agent


def _agent(n_inputs: int, xy: bool):
    """A high-level learner a few trials into learning, so its choices vary (a random net's are dull)."""
    agent = make_high_level_agent(RechargeParams(), np.random.default_rng(3), n_inputs=n_inputs)
    env = BehaviourEnv(_shipped_library(), max_steps=60, xy=xy)
    for k in range(3):
        run_trial(env, agent, trial=k, learning=True, seed=200 + k)
    return agent


@pytest.mark.parametrize("world", [{}, {"step_scale": 0.2, "max_steps": 150}, {"xy": False}, {"xy_scale": 8.0}])
def test_the_compiled_play_is_run_trials_play(world):
    world = {"max_steps": 120, **world}
    agent = _agent(16 if world.get("xy", True) else 14, world.get("xy", True))
    env, ref_env = BehaviourEnv(_shipped_library(), **world), BehaviourEnv(_shipped_library(), **world)
    assert recharge_play.compiled(env, agent)
    rng, collided = np.random.default_rng(0), 0
    for k in range(8):
        start, seed = sample_in_room(rng, env.world.layout, ROOMS[k % 3]), int(rng.integers(2**31))
        hits = []
        ref = run_trial(ref_env, agent, trial=0, learning=False, seed=seed, options={"start": start},
                        on_step=lambda info, hits=hits: hits.append(info["collision"]))
        ref_agent = (agent._x.copy(), agent.last_q.copy(), agent.last_probabilities.copy())
        got, got_hits = recharge_play.greedy_play(env, agent, seed, start)
        assert (got.steps, got.total_reward, got.terminated, got.truncated, got.info["success"], got_hits) == (
            ref.steps, ref.total_reward, ref.terminated, ref.truncated, ref.info["success"], sum(hits))
        for value, ref_value in zip((agent._x, agent.last_q, agent.last_probabilities), ref_agent, strict=True):
            np.testing.assert_array_equal(value, ref_value)
        w, ref_w = env.world, ref_env.world
        assert (w.trace, w.sim.pose, w.sim.last_action, w._steps) == (
            ref_w.trace, ref_w.sim.pose, ref_w.sim.last_action, ref_w._steps)
        np.testing.assert_array_equal(w.sim.last_collision, ref_w.sim.last_collision)
        assert env._task_obs.keys() == ref_env._task_obs.keys()
        for task, obs in ref_env._task_obs.items():
            np.testing.assert_array_equal(env._task_obs[task], obs)
            assert env._task_obs[task].dtype == obs.dtype
        assert w.np_random.bit_generator.state == ref_w.np_random.bit_generator.state
        collided += got_hits
    assert collided > 0  # the partial moves' contact arithmetic was exercised


def test_other_learners_and_worlds_play_through_run_trial():
    agent = _agent(16, True)
    assert not recharge_play.compiled(BehaviourEnv(_shipped_library(), obs="high").world, agent)  # primitives
    from connrl.tasks.recharge_together import TrainingBehaviourEnv
    assert not recharge_play.compiled(TrainingBehaviourEnv.__new__(TrainingBehaviourEnv), agent)
    env = BehaviourEnv(_shipped_library())
    assert recharge_play.compiled(env, agent)
    assert not recharge_play.compiled(env, object())
