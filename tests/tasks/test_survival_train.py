"""Ch. 4's compiled training play is run_trial's play, step for step: the same steps and outcome, the same nets,
lessons, stuck detector and learner left behind, and the same two random streams, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.core.rollout import run_trial
from connrl.envs.survival import SurvivalEnv
from connrl.tasks.survival import FoodReward, SurvivalAgentParams, make_survival_agent
from connrl.tasks.survival_train import _compiled_nets, learning_play


def _pair(framework, representation="global", symmetry=True, max_steps=None, model="learned"):
    """Two identical agents, each with its own world."""
    params = SurvivalAgentParams(framework, representation, model, symmetry=symmetry, plays=20, model_start=2)
    out = []
    for _ in range(2):
        env = SurvivalEnv(representation, max_steps=max_steps)
        env.reset(seed=11)
        out.append((env, make_survival_agent(params, env, np.random.default_rng(5))))
    return out


def _nets(agent):
    nets = [agent.q] if hasattr(agent, "q") else [agent.v, agent.policy]
    return [a for n in nets for a in n.state_dict().values()] + [n.net.d1 if hasattr(n, "net") else n.d1 for n in nets]


def _assert_same(agent, ref):
    for got, want in zip(_nets(agent), _nets(ref), strict=True):
        np.testing.assert_array_equal(got, want)
    assert agent.rng.bit_generator.state == ref.rng.bit_generator.state
    np.testing.assert_array_equal(agent._x, ref._x)
    np.testing.assert_array_equal(agent.last_probabilities, ref.last_probabilities)
    e, r = agent.explore, ref.explore
    assert (e._rows, e._cols, e._food, e.boosted) == (r._rows, r._cols, r._food, r.boosted)
    if ref.planner is not None:
        _assert_same_planner(agent.planner, ref.planner)
    mem, ref_mem = agent.book.memory, ref.book.memory
    if ref_mem is not None:
        assert len(mem) == len(ref_mem)
        for a, b in zip(mem.lessons, ref_mem.lessons, strict=True):
            for got, want in ((a.inputs, b.inputs), (a.actions, b.actions), (a.rewards, b.rewards)):
                assert got.dtype == want.dtype
                np.testing.assert_array_equal(got, want)
            assert (a.terminated, a.truncated) == (b.terminated, b.truncated)


def _assert_same_planner(planner, ref):
    assert (planner.steps, planner.hypothetical) == (ref.steps, ref.hypothetical)
    model, ref_model = planner.model, ref.model
    learned = hasattr(ref_model, "w_r")
    for name in ("w_r", "w_e", "d_r", "d_e", "_q") if learned else ():
        np.testing.assert_array_equal(getattr(model, name), getattr(ref_model, name))
    if learned:
        assert (model._n, model.errors) == (ref_model._n, ref_model.errors)
    scratch, ref_scratch = (model.sim if learned else model).scratch, (ref_model.sim if learned else ref_model).scratch
    state, ref_state = scratch.get_state(include_rng=True), ref_scratch.get_state(include_rng=True)
    for key in ref_state.keys() - {"done"}:  # the loop leaves the scratch world's done flag unset: set_state sets it
        assert str(state[key]) == str(ref_state[key]), key


def _play_both(pair, plays, start=0):
    (env, agent), (ref_env, ref) = pair
    boosted = 0
    for k in range(start, start + plays):
        got = learning_play(env, agent, trial=k, options={"layout_seed": 100 + k})
        want = run_trial(ref_env, ref, trial=k, learning=True, options={"layout_seed": 100 + k})
        assert (got.steps, got.total_reward, got.terminated, got.truncated, got.info) == (
            want.steps, want.total_reward, want.terminated, want.truncated, want.info)
        _assert_same(agent, ref)
        if hasattr(getattr(ref.planner, "model", None), "pop_errors"):  # as run_survival reads them, play by play
            assert agent.planner.model.pop_errors() == ref.planner.model.pop_errors()
        state, ref_state = env.get_state(include_rng=True), ref_env.get_state(include_rng=True)
        for key, value in ref_state.items():
            assert str(state[key]) == str(value), key
        boosted += ref.explore.boosted
    return boosted


@pytest.mark.parametrize("framework,representation,symmetry", [
    ("QCON", "global", True), ("AHCON", "global", True), ("QCON-R", "local", True), ("AHCON-T", "local", True),
    ("QCON", "global", False)])
def test_the_compiled_training_play_is_run_trials_play(framework, representation, symmetry):
    pair = _pair(framework, representation, symmetry)
    assert _compiled_nets(*pair[0], 0) is not None
    assert _play_both(pair, 8) > 0  # the stuck detector raised T on some steps


@pytest.mark.parametrize("framework,representation,model", [
    ("QCON-M", "global", "perfect"), ("QCON-M", "local", "learned"), ("AHCON-M", "global", "learned"),
    ("AHCON-M", "local", "perfect")])
def test_the_compiled_planning_play_is_run_trials_play(framework, representation, model):
    pair = _pair(framework, representation, model=model)
    for _, agent in pair if model == "learned" else ():
        agent.planner.model._q = np.zeros((40, agent.planner.model._q.shape[1]))  # a queue that wraps in the test
    assert _compiled_nets(*pair[0], 0) is not None
    _play_both(pair, 5)
    assert pair[1][1].planner.hypothetical > 0  # the last play planned


def test_plays_cut_by_the_time_limit_are_run_trials_plays():
    pair = _pair("QCON-R", max_steps=15)
    _play_both(pair, 4)
    assert pair[0][1].book.memory.lessons[-1].truncated


def test_other_agents_and_worlds_play_through_run_trial():
    env = SurvivalEnv("global")
    planner = make_survival_agent(SurvivalAgentParams("QCON-M", model="perfect"), env, np.random.default_rng(1))
    assert _compiled_nets(SurvivalEnv("global"), planner, 0) is None  # its model simulates another world
    agent = make_survival_agent(SurvivalAgentParams("QCON"), env, np.random.default_rng(1))
    assert _compiled_nets(FoodReward(env, 0.5), agent, 0) is None
    stats = learning_play(FoodReward(env, 0.5), agent, trial=0, seed=3, options={"layout_seed": 3})
    assert stats.steps > 0
    agent.observe = agent.observe  # a method replaced on the instance: the loop would not call it
    assert _compiled_nets(env, agent, 1) is None
    del agent.observe

    class OwnQCON(type(agent)):
        pass

    agent.__class__ = OwnQCON
    assert _compiled_nets(env, agent, 1) is None
