"""The value scale of connrl.own.api (connrl.own.value_scale, issue 29): the rule on hand-made rewards, the provisional
range set by the first reward, growth by larger ones, save / load, and a small sparse-reward grid the defaults solve
where the old rule (max |reward| / (1 - gamma)) did not."""

import json
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from gymnasium.wrappers import TimeLimit

import connrl
import connrl.own.api
from connrl.own.api import make_agent
from connrl.own.value_scale import range_for, rescale, reward_sizes


class Grid(gym.Env):
    """An n x n grid from (0, 0) to the goal (n-1, n-1), worth ``goal`` and ending the episode; no other reward."""

    action_space = spaces.Discrete(4)

    def __init__(self, n=4, goal=1.0):
        self.n, self.goal = n, goal
        self.observation_space = spaces.Discrete(n * n)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.pos = (0, 0)
        return 0, {}

    def step(self, a):
        dr, dc = ((-1, 0), (1, 0), (0, -1), (0, 1))[int(a)]
        self.pos = (min(max(self.pos[0] + dr, 0), self.n - 1), min(max(self.pos[1] + dc, 0), self.n - 1))
        done = self.pos == (self.n - 1, self.n - 1)
        return self.pos[0] * self.n + self.pos[1], self.goal if done else 0.0, done, False, {}


def grid(n=5, goal=1.0, limit=40):
    return TimeLimit(Grid(n, goal), limit)


def test_the_rule_on_hand_made_rewards():
    # (reward, terminated) pairs: a reward that ends the episode counts once, one that can recur 1 / (1 - gamma) times
    assert reward_sizes([(0.0, False), (0.0, False), (1.0, True)]) == (0.0, 1.0)
    assert range_for(0.0, 1.0, 0.99) == pytest.approx(1.0)  # a goal's +1: 1, where the old rule gave 100
    assert range_for(*reward_sizes([(1.0, False), (1.0, True)]), 0.99) == pytest.approx(100.0)  # CartPole: as before
    assert range_for(*reward_sizes([(-0.5, False), (10.0, True)]), 0.9) == pytest.approx(10.0)  # max(0.5 / 0.1, 10)
    assert range_for(*reward_sizes([(-2.0, False), (-10.0, True), (3.0, False)]), 0.9) == pytest.approx(30.0)
    assert range_for(0.5, 0.0, 1.0) == pytest.approx(500.0)  # gamma = 1: 1 / (1 - gamma) taken as at most 1,000
    assert range_for(*reward_sizes([(0.0, False), (0.0, True)]), 0.99) is None  # no reward seen: not set yet
    assert reward_sizes([]) == (0.0, 0.0)


def test_make_agent_sets_the_range_from_the_warm_up_and_keeps_the_temperature_relative():
    agent = make_agent(grid(3), "QCON-R", seed=0, warmup_steps=300)  # a random walk reaches a 3 x 3 goal
    assert agent.range_set and agent.value_range == pytest.approx(1.0)
    assert agent.temperature(0) == pytest.approx(0.05)
    assert make_agent(grid(3, goal=4.0), seed=0, warmup_steps=300).value_range == pytest.approx(4.0)
    assert make_agent(grid(3), seed=0, value_range=7.0).value_range == 7.0  # the user's range is kept


def test_the_first_reward_sets_a_provisional_range_and_rescales_every_q_value():
    agent = make_agent(grid(8, goal=10.0, limit=20), "QCON-R", seed=0, warmup_steps=20)  # 20 steps: no goal
    assert not agent.range_set and agent.value_range == 1.0
    x = agent.scaler.encode(5)
    before = agent.learner.q.values(x)
    agent._check_range((0.0, 10.0))  # what learn() calls when a reward of 10 ends an episode
    assert agent.range_set and agent.value_range == pytest.approx(10.0)
    np.testing.assert_allclose(agent.learner.q.values(x), 10.0 * before)
    assert agent.temperature(0) == pytest.approx(0.05 * 10.0)


def test_larger_rewards_grow_the_range_keeping_q_and_a_range_the_user_set_is_kept_with_a_warning():
    agent = make_agent(grid(8, goal=10.0, limit=20), "QCON-R", seed=0, warmup_steps=20)
    agent._check_range((0.0, 10.0))
    x = agent.scaler.encode(5)
    before = agent.learner.q.values(x)
    agent._check_range((0.0, 5.0))  # no larger return: nothing changes
    np.testing.assert_array_equal(agent.learner.q.values(x), before)
    agent._check_range((0.5, 10.0))  # a step reward of 0.5 allows 0.5 / (1 - 0.99) = 50
    assert agent.value_range == pytest.approx(50.0)
    np.testing.assert_allclose(agent.learner.q.values(x), before, rtol=0.05)  # kept (to first order)
    assert not np.allclose(agent.learner.q.values(x), 5 * before, rtol=0.5)  # not scaled with the range
    fixed = make_agent(grid(8, limit=20), "QCON-R", seed=0, warmup_steps=20, value_range=1.0)
    with pytest.warns(RuntimeWarning, match="a reward of 0.5 allows returns up to 50, beyond value_range"):
        fixed._check_range((0.5, 0.0))
    assert fixed.value_range == 1.0


def test_rescale_changes_every_net_of_every_kind():
    for kind in ("QCON-R", "AHCON-R", "recurrent-Q"):
        agent = make_agent(grid(8, limit=20), kind, seed=0, warmup_steps=20)
        assert not agent.range_set, kind
        state = {k: v.copy() for k, v in agent.nets.state_dict().items()}
        rescale(connrl.own.api._all_nets(agent), 3.0)
        assert all(net.scale == 6.0 for net in connrl.own.api._all_nets(agent)), kind
        assert all(np.array_equal(state[k], v) for k, v in agent.nets.state_dict().items()), kind  # weights kept


def test_a_provisional_range_survives_save_and_load_and_older_files_load_as_set(tmp_path):
    agent = make_agent(grid(8, limit=20), "QCON-R", seed=0, warmup_steps=20)
    agent.save(tmp_path / "a")
    assert json.loads((tmp_path / "a" / "agent.json").read_text())["range_set"] is False
    b = connrl.load(tmp_path / "a", grid(8, limit=20))
    assert not b.range_set and b.value_range == 1.0
    meta = tmp_path / "a" / "agent.json"
    m = json.loads(meta.read_text())
    del m["range_set"]  # a file written before the field: its range was set by the old rule, and stays
    meta.write_text(json.dumps(m))
    assert connrl.load(tmp_path / "a").range_set
    m["range_set"] = "no"
    meta.write_text(json.dumps(m))
    with pytest.raises(ValueError, match="range_set"):
        connrl.load(tmp_path / "a")


def _solves(seed, steps=10_000):
    env = grid()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        agent = make_agent(env, "QCON-R", seed=seed).learn(steps)
    return connrl.evaluate(agent, env, episodes=1)[0] == 1.0


def test_the_defaults_solve_a_small_sparse_grid_on_three_seeds():
    assert [_solves(seed) for seed in (0, 1, 2)] == [True, True, True]


def test_the_old_rule_fails_the_same_grid(monkeypatch):
    # the test above can fail: with value_range = max |reward| / (1 - gamma) (100 for the goal's +1) it does
    monkeypatch.setattr(connrl.own.api, "range_for", lambda s, e, gamma: max(s, e, 1e-3) / max(1 - gamma, 1e-3))
    assert not all(_solves(seed) for seed in (0, 1, 2))
