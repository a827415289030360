"""Ch. 7's compiled cup trials are run_trial's, step for step: the same training trials (steps, reward, outcome, nets,
lessons, model, learner and world left behind, both random streams) and the same greedy test scores and wasted
pick-ups, bit for bit; and anything but the plain case plays through run_trial."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.core.rollout import run_trial
from connrl.envs.cup import CupCollectionEnv
from connrl.experiments.hidden_state import CupParams
from connrl.tasks import cup_play, hidden_state
from connrl.tasks.hidden_state import make_agent, make_cup_envs
from tests.tasks.test_robot_train import assert_same_lessons


def _parts(agent) -> dict:
    nets = {name: getattr(agent, name) for name in ("q", "model", "net") if hasattr(agent, name)}
    out = {}
    for name, net in nets.items():
        for field in ("w1", "w2", "d1", "d2", "context", "_h_all", "_y"):
            if hasattr(net, field):
                out[f"{name}.{field}"] = getattr(net, field)
    return out


def _assert_same_agents(agent, ref):
    mine = _parts(agent)
    for name, value in _parts(ref).items():
        np.testing.assert_array_equal(mine[name], value, err_msg=name)
    assert agent.rng.bit_generator.state == ref.rng.bit_generator.state
    assert getattr(agent, "_last_action", None) == getattr(ref, "_last_action", None)
    if hasattr(ref, "memory"):
        np.testing.assert_array_equal(agent.memory.sensations, ref.memory.sensations)
        np.testing.assert_array_equal(agent.memory.actions, ref.memory.actions)
    for name in ("_x", "_xq", "last_probabilities", "_last_obs"):
        if hasattr(ref, name):
            np.testing.assert_array_equal(getattr(agent, name), getattr(ref, name), err_msg=name)
    assert_same_lessons(agent, ref)


def _assert_same_worlds(env, ref_env):
    w, ref_w = env.unwrapped, ref_env.unwrapped
    assert (w.position, w.cups, w._collision, w._steps, w._done) == (
        ref_w.position, ref_w.cups, ref_w._collision, ref_w._steps, ref_w._done)
    assert w.np_random.bit_generator.state == ref_w.np_random.bit_generator.state


@pytest.mark.parametrize(("task", "arch", "changes"), [
    (1, "recurrent-model", {}), (2, "recurrent-model", {}), (3, "recurrent-model", {"model_lessons_per_trial": 3}),
    (2, "recurrent-model", {"online": False}), (1, "recurrent-Q", {}), (2, "recurrent-Q", {}), (3, "recurrent-Q", {}),
    (1, "window-Q", {}), (2, "window-Q", {"lam": 0.0}), (3, "window-Q", {"online": False}),
    (2, "window-Q", {"table": {"hq": 4}})])
def test_the_compiled_trials_are_run_trials(task, arch, changes, monkeypatch):
    p = CupParams(task=task, arch=arch, trials=30, lessons_per_trial=4, **changes)
    pairs = []
    for _ in range(2):
        train_env, test_env = make_cup_envs(task)
        train_env.reset(seed=11)
        test_env.reset(seed=12)
        pairs.append((train_env, test_env, make_agent(p, train_env.observation_space.shape[0], 3,
                                                      np.random.default_rng(5))))
    (env, test_env, agent), (ref_env, ref_test_env, ref) = pairs
    reference, reference_score = run_trial, hidden_state.test_score
    monkeypatch.setattr(cup_play, "run_trial", _refused)  # every trial and test below must be compiled
    monkeypatch.setattr(hidden_state, "test_score", _refused)
    outcomes, picked = set(), False
    for k in range(25):
        got = cup_play.learning_play(env, agent, trial=k)
        want = reference(ref_env, ref, trial=k, learning=True)
        assert (got.steps, got.total_reward, got.terminated, got.truncated) == (
            want.steps, want.total_reward, want.terminated, want.truncated)
        _assert_same_worlds(env, ref_env)
        _assert_same_agents(agent, ref)
        outcomes.add(got.terminated)
        picked |= len(ref_env.unwrapped.cups) < 2
        if k % 4 == 0:
            test_env.wasted = ref_test_env.wasted = 0
            assert cup_play.test_score(test_env, agent) == reference_score(ref_test_env, ref)
            assert test_env.wasted == ref_test_env.wasted
            _assert_same_worlds(test_env, ref_test_env)
            _assert_same_agents(agent, ref)
    assert picked and False in outcomes  # trials that collected cups and trials that timed out


def _refused(*args, **kwargs):
    raise AssertionError("this trial was to be compiled, not played through the Python path")


def test_a_test_world_with_control_errors_counts_failed_pick_ups_as_wasted():
    """``WastedPickUps`` counts a pick-up that collects nothing, a failed one too: so does the compiled test."""
    agent = make_agent(CupParams(task=3, arch="recurrent-Q"), 4, 3, np.random.default_rng(2))
    agent.net.w2[2, 0, -1] += 3.0  # pick-up preferred everywhere: many pick-ups, some of them failed
    envs = [hidden_state.WastedPickUps(CupCollectionEnv(control_error=0.5)) for _ in range(2)]
    for env in envs:
        env.reset(seed=4)
    assert cup_play.compiled(envs[0], agent)
    for _ in range(3):
        assert cup_play.test_score(envs[0], agent) == hidden_state.test_score(envs[1], agent)
        assert envs[0].wasted == envs[1].wasted > 0
        _assert_same_worlds(envs[0], envs[1])


def test_other_learners_and_worlds_play_through_run_trial(monkeypatch):
    p = CupParams(task=2, arch="window-Q", trials=5)
    env, test_env = make_cup_envs(2)
    env.reset(seed=1)
    window = make_agent(p, env.observation_space.shape[0], 3, np.random.default_rng(0))
    assert cup_play.compiled(env, window)
    window.__class__ = type("OwnWindowQ", (type(window),), {})  # a subclass may do anything differently
    assert not cup_play.compiled(env, window)
    played = []
    monkeypatch.setattr(cup_play, "run_trial", lambda *a, **kw: played.append(a) or run_trial(*a, **kw))
    cup_play.learning_play(env, window, trial=0)
    assert len(played) == 1  # through run_trial
    agent = make_agent(CupParams(task=2, arch="recurrent-model"), env.observation_space.shape[0], 3,
                       np.random.default_rng(0))
    assert cup_play.compiled(env, agent)
    for part, name in ((agent, "act"), (agent, "q_input"), (agent.q, "update"), (agent.model, "step"),
                       (agent.explore, "temperature"), (agent.book.recorder, "add")):
        setattr(part, name, getattr(part, name))  # a method replaced on the instance: the loop would not call it
        assert not cup_play.compiled(env, agent)
        delattr(part, name)
    assert not cup_play.compiled(make_cup_envs(1)[0], agent)  # a world without the random bits its nets read
