"""Ch. 4's compiled greedy test play is run_trial's play, step for step: the same steps, reward, outcome and world,
the same input left with the agent, and the same random stream left behind."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.core.rollout import run_trial
from connrl.envs.survival import SurvivalEnv
from connrl.tasks.survival import SurvivalAgentParams, make_survival_agent
from connrl.tasks.survival_play import greedy_net, greedy_play


def _trained(framework: str, representation: str = "global"):
    """An agent a few plays into learning (a random net plays short, dull games)."""
    env = SurvivalEnv(representation)
    agent = make_survival_agent(SurvivalAgentParams(framework, representation), env, np.random.default_rng(3))
    for k in range(6):
        run_trial(env, agent, trial=k, learning=True, seed=100 + k, options={"layout_seed": 100 + k})
    return agent


@pytest.mark.parametrize("framework", ["QCON", "AHCON", "QCON-R"])
@pytest.mark.parametrize("max_steps", [None, 25])
def test_the_compiled_play_is_run_trials_play(framework, max_steps):
    agent = _trained(framework)
    assert greedy_net(agent) is not None
    for k in range(10):
        env, ref_env = SurvivalEnv("global", max_steps=max_steps), SurvivalEnv("global", max_steps=max_steps)
        ref = run_trial(ref_env, agent, trial=0, learning=False, seed=k, options={"layout_seed": k})
        ref_x, ref_p = agent._x.copy(), agent.last_probabilities.copy()
        got = greedy_play(env, agent, k)
        assert (got.steps, got.total_reward, got.terminated, got.truncated, got.info) == (
            ref.steps, ref.total_reward, ref.terminated, ref.truncated, ref.info)
        np.testing.assert_array_equal(agent._x, ref_x)
        np.testing.assert_array_equal(agent.last_probabilities, ref_p)
        state, ref_state = env.get_state(include_rng=True), ref_env.get_state(include_rng=True)
        assert state.keys() == ref_state.keys()
        for key, value in ref_state.items():
            assert str(state[key]) == str(value), key
    assert got.truncated or max_steps is None  # the short plays end at the time limit


def test_other_agents_and_worlds_play_through_run_trial():
    agent = _trained("QCON", "local")  # one net per action: no rotated net to compile
    assert greedy_net(agent) is None
    got = greedy_play(SurvivalEnv("local"), agent, 3)
    ref = run_trial(SurvivalEnv("local"), agent, trial=0, learning=False, seed=3, options={"layout_seed": 3})
    assert (got.steps, got.info) == (ref.steps, ref.info)
