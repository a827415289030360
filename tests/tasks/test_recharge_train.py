"""Chs. 6 and 8's compiled training trial over behaviours is run_trial's trial, step for step: the same steps, reward
and outcome, the same nets, lessons (with each step's W and each state's applicability), choices, world and learner
left behind, the same two random streams, bit for bit; and anything but the plain case plays through run_trial."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from connrl.core.rollout import run_trial
from connrl.envs.robot.recharge import ROOMS
from connrl.experiments.integration import IntegrationParams
from connrl.experiments.recharge import RechargeParams, _test
from connrl.tasks import recharge_train
from connrl.tasks.integration import make_integration_agent, make_integration_env
from connrl.tasks.recharge import make_high_level_agent, make_recharge_env
from connrl.tasks.recharge_train import compiled_learning, learning_play
from tests.tasks.test_recharge_play import _starts, assert_same_worlds
from tests.tasks.test_robot_train import assert_same_lessons


def _nets(agent) -> dict:
    net = getattr(agent, "q", None) or agent.net
    out = {name: getattr(net, name) for name in ("w1", "w2", "d1", "d2")}
    if hasattr(agent, "net"):
        out |= {"context": net.context, "h_all": net._h_all, "y": net._y}
    return out


def _assert_same_agents(agent, ref):
    for name, value in _nets(ref).items():
        np.testing.assert_array_equal(_nets(agent)[name], value, err_msg=name)
    assert agent.rng.bit_generator.state == ref.rng.bit_generator.state
    for name in ("_x", "last_q", "last_probabilities"):
        np.testing.assert_array_equal(getattr(agent, name), getattr(ref, name), err_msg=name)
    c, ref_c = agent.choice, ref.choice
    assert c._active == ref_c._active
    np.testing.assert_array_equal(c._was_applicable, ref_c._was_applicable)
    np.testing.assert_array_equal(c._w, ref_c._w)
    assert_same_lessons(agent, ref, meta=("weights", "applicable"))


CASES = [
    ("ch6", {}),  # Exp. 3: persistence, on-line, the applicable max
    ("ch6", {"target_clip": 40.0}),  # on-line targets cut off (4.2.4's rule; Ch. 6 does not use it)
    ("ch6", {"persistence": False, "target_max": "all"}),  # Exp. 2
    ("ch6", {"online": False, "step_scale": 0.2, "success_reward": 500.0, "grouping": True}),  # Exp. 4
    ("ch8", {}),  # Exp. 1: memoryless without X-Y
    ("ch8", {"memory": "recurrent", "online": False}),  # Exp. 2: recurrent-Q
    ("ch8", {"memory": "recurrent", "online": False, "share_output": True, "xy": True, "persistence": False}),
]


def _pair(kind, changes):
    clip = changes.pop("target_clip", None)
    pairs = _made(kind, changes)
    for _, agent in pairs:
        agent.config = dataclasses.replace(agent.config, target_clip=clip)
    return pairs


def _made(kind, changes):
    if kind == "ch6":
        p = dataclasses.replace(RechargeParams(), max_steps=90, lessons_per_trial=5, **changes)
        return [(make_recharge_env(p), make_high_level_agent(p, np.random.default_rng(7))) for _ in range(2)]
    p = dataclasses.replace(IntegrationParams(), max_steps=90, lessons_per_trial=5, **changes)
    return [(make_integration_env(p), make_integration_agent(p, np.random.default_rng(7))) for _ in range(2)]


@pytest.mark.parametrize(("kind", "changes"), CASES)
def test_the_compiled_training_trial_is_run_trials_trial(kind, changes, monkeypatch):
    (env, agent), (ref_env, ref) = _pair(kind, dict(changes))
    reference = run_trial
    monkeypatch.setattr(recharge_train, "run_trial", _refused)  # every trial below must be compiled
    ended, chosen = set(), set()
    for k in range(8):
        got = learning_play(env, agent, trial=k, seed=500 + k)
        want = reference(ref_env, ref, trial=k, learning=True, seed=500 + k)
        assert (got.steps, got.total_reward, got.terminated, got.truncated, got.info["success"]) == (
            want.steps, want.total_reward, want.terminated, want.truncated, want.info["success"])
        assert_same_worlds(env, ref_env)
        _assert_same_agents(agent, ref)
        ended.add(got.terminated)
        chosen.update(ref.book.memory.lessons[-1].actions.tolist())
    assert len(chosen) >= 3  # the trials chose among behaviours
    if kind == "ch6" and changes.get("persistence", True):
        assert any((x.meta["weights"] == 100.0).any() for x in ref.book.memory.lessons)  # persistence acted


def _refused(*args, **kwargs):
    raise AssertionError("this trial was to be compiled, not played by run_trial")


def test_other_learners_and_trials_play_through_run_trial(monkeypatch):
    (env, agent), _ = _pair("ch6", {})
    seen = []
    stats = learning_play(env, agent, trial=0, seed=1, on_step=seen.append)
    assert len(seen) == stats.steps
    assert compiled_learning(env, agent, 1)
    for part, name in ((agent, "act"), (agent.q, "update"), (agent.explore, "temperature"),
                       (agent.book.recorder, "add"), (agent.choice, "choose")):
        setattr(part, name, getattr(part, name))  # a method replaced on the instance: the loop would not call it
        assert not compiled_learning(env, agent, 1)
        delattr(part, name)
    assert not compiled_learning(env.world, agent, 1)  # the world of primitives
    (renv, ragent), _ = _pair("ch8", {"memory": "recurrent", "online": False})
    assert compiled_learning(renv, ragent, 0)
    ragent.net.advance = ragent.net.advance
    assert not compiled_learning(renv, ragent, 0)
    assert not compiled_learning(renv, agent, 0)  # 16 inputs on a 14-unit world
    monkeypatch.setattr(recharge_train, "weighted_choice_fits", lambda n: False)
    assert not compiled_learning(env, agent, 1)



@pytest.mark.parametrize("changes", [{}, {"xy": True, "share_output": True, "persistence": False}])
def test_the_compiled_recurrent_test_play_is_run_trials_play(changes, monkeypatch):
    """Ch. 8's greedy tests of recurrent-Q: the same steps, reward, outcome and collisions, the same world and learner
    left behind; and the protocol's tests give the same totals either way."""
    (env, agent), (ref_env, _) = _pair("ch8", {"memory": "recurrent", "online": False, **changes})
    for k in range(3):
        run_trial(env, agent, trial=k, learning=True, seed=40 + k)
    assert recharge_train.compiled_greedy(env, agent)
    assert not recharge_train.compiled_greedy(env, make_high_level_agent(RechargeParams(), np.random.default_rng(0)))
    rng, chosen, ended = np.random.default_rng(0), set(), set()
    for start in _starts(env, rng, 8):
        seed, hits = int(rng.integers(2**31)), []
        got, got_hits = recharge_train.greedy_play(env, agent, seed, start)
        mine = (agent._x.copy(), agent.last_q.copy(), agent.last_probabilities.copy(), agent.net.context.copy(),
                agent.net._h_all.copy(), agent.net._y.copy())
        ref = run_trial(ref_env, agent, trial=0, learning=False, seed=seed, options={"start": start},
                        on_step=lambda info, hits=hits: (hits.append(info["collision"]), chosen.add(info["behaviour"])))
        assert (got.steps, got.total_reward, got.terminated, got.truncated, got.info["success"], got_hits) == (
            ref.steps, ref.total_reward, ref.terminated, ref.truncated, ref.info["success"], sum(hits))
        theirs = (agent._x, agent.last_q, agent.last_probabilities, agent.net.context, agent.net._h_all, agent.net._y)
        for value, ref_value in zip(mine, theirs, strict=True):
            np.testing.assert_array_equal(value, ref_value)
        assert_same_worlds(env, ref_env)
        ended.add(got.terminated)
    assert len(chosen) >= 2 and True in ended  # choices among behaviours, and dockings
    tasks = [(ROOMS[k % 3], s) for k, s in enumerate(_starts(env, rng, 6))]
    seeds = rng.integers(2**31, size=len(tasks))
    fast = _test(env, agent, tasks, seeds)
    monkeypatch.setattr(recharge_train, "compiled_greedy", lambda env, agent: False)
    assert _test(env, agent, tasks, seeds) == fast
