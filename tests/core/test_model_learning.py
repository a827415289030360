"""Greedy-mapping model learning (6.2.1): executions counted by hand on tiny grids, episodes with resets (6.2.2)."""

import numpy as np
import pytest

from connrl.core.hierarchy import abstract_graph, ball
from connrl.core.model_learning import RULES, LocalWorld, greedy_mapping_reference, learn_model
from connrl.envs.grid import GridWorld


def test_a_line_of_three_from_its_end_by_hand():
    g = GridWorld(3, 1)  # actions: 0 = +1, 1 = -1; a step off the line stays
    # from 0: +1 (->1), +1 (->2), +1 (stays), -1 (->1), -1 (->0), -1 (stays): every try is where the agent stands
    assert learn_model(g.next_state, starts=np.array([0])) == 6
    # from 2: +1 (stays), -1 (->1), +1 (->2), walk 1 back, -1 (->0), +1 (->1), walk 1 back, -1 (stays)
    assert learn_model(g.next_state, starts=np.array([2])) == 8


def test_every_state_action_is_tried_once_and_walks_are_few_on_a_grid():
    g = GridWorld(10, 2)
    n_tries = g.n * g.n_actions
    total = learn_model(g.next_state, seed=3)
    assert n_tries <= total < 2 * n_tries  # O(b n) is the worst case; on a grid the walks stay short


def test_episodes_from_resets_try_only_the_target_and_stop_after_their_budget():
    g = GridWorld(5, 1)
    target = np.zeros(5, bool)
    target[2] = True
    # one execution per episode from state 2: +1 then (a new episode, reset to 2) -1
    assert learn_model(g.next_state, target=target, starts=np.array([2]), episode=1) == 2
    # the abstract action's vicinity: states 1..3 from resets within 1 of state 2, episodes of 1 step
    target[[1, 3]] = True
    assert learn_model(g.next_state, target=target, starts=np.array([1, 2, 3]), episode=1, seed=0) == 6


def test_weighted_actions_count_their_cost():
    succ = np.array([[1], [0]])  # two states, one action each way
    assert learn_model(succ, cost=np.array([[4], [4]]), starts=np.array([0])) == 8


def test_deterministic_given_the_seed_and_bad_tables_refused():
    g = GridWorld(8, 2)
    assert learn_model(g.next_state, seed=5) == learn_model(g.next_state, seed=5)
    with pytest.raises(ValueError, match="succ must be"):
        learn_model(np.array([[5]]))
    with pytest.raises(ValueError, match="cost must"):
        learn_model(np.array([[0]]), cost=np.array([[0]]))


def test_a_random_walk_needs_far_more_executions_than_greedy_mapping():
    g = GridWorld(30, 1)
    greedy = learn_model(g.next_state, seed=1)
    walks = [learn_model(g.next_state, seed=s, rule="random") for s in range(5)]
    assert greedy < 2 * g.n * g.n_actions and min(walks) > greedy  # a walk's cover time on a line grows as n^2
    with pytest.raises(ValueError, match="rule must be one of"):
        learn_model(g.next_state, rule="smart")


@pytest.mark.parametrize("side,start", [(4, 0), (6, 17), (7, 48)])
def test_greedy_mapping_matches_a_plain_reference_over_a_whole_run(side, start):
    # the compiled search resets only the states its last search visited; a stale distance would change the count
    g = GridWorld(side, 2)
    assert learn_model(g.next_state, starts=np.array([start])) == greedy_mapping_reference(g.next_state, start)


@pytest.mark.parametrize("rule", RULES)
@pytest.mark.parametrize("dim,side,l", [(1, 40, 3), (2, 12, 3), (2, 9, 1)])
def test_a_local_world_counts_what_the_whole_table_counts(rule, dim, side, l):
    g = GridWorld(side, dim)
    world = LocalWorld(g.next_state)
    for seed, c in enumerate(range(0, g.n, max(1, g.n // 7))):
        states, _ = ball(g.next_state, c, l)
        target = np.zeros(g.n, bool)
        target[states] = True
        whole = learn_model(g.next_state, target=target, starts=states, episode=l, stop_at=c, seed=seed, rule=rule)
        assert world.explore(states, states, l, c, seed=seed, rule=rule) == whole


@pytest.mark.parametrize("rule", RULES)
def test_a_local_world_with_costly_actions_counts_what_the_whole_table_counts(rule):
    # an abstract level (6.2.3): actions cost their path lengths (3 or 6), so a route may not fit what is left of
    # an episode and the part within reach ends at actions that lead out of it
    g = GridWorld(40, 1)
    succ, cost = abstract_graph(g.next_state, np.arange(1, 40, 3), 6)
    world = LocalWorld(succ, cost)
    for seed, c in enumerate(range(succ.shape[0])):
        mine = np.array(sorted({c, max(c - 1, 0)}))
        target = np.zeros(succ.shape[0], bool)
        target[mine] = True
        whole = learn_model(succ, cost, target=target, starts=mine, episode=7, stop_at=c, seed=seed, rule=rule)
        assert world.explore(mine, mine, 7, c, seed=seed, rule=rule) == whole
    with pytest.raises(ValueError, match="episode must be >= 1"):
        world.explore(mine, mine, 0)
    with pytest.raises(ValueError, match="can never be tried"):  # an action dearer than an episode
        learn_model(succ, cost, target=target, starts=mine, episode=5)


def test_a_local_world_on_random_tables_counts_what_the_whole_table_counts():
    # random costs and absent actions, repeated starts, targets fewer than the starts, stop_at anywhere (or none)
    rng = np.random.default_rng(0)
    checked = 0
    while checked < 60:
        n, k, episode = int(rng.integers(5, 30)), int(rng.integers(1, 4)), int(rng.integers(2, 7))
        succ = rng.integers(0, n, (n, k))
        succ[rng.random((n, k)) < 0.15] = -1
        succ[:, 0] = np.where(succ[:, 0] < 0, np.arange(n), succ[:, 0])  # every state keeps an action
        cost = rng.integers(1, 3, (n, k))
        starts = rng.integers(0, n, int(rng.integers(1, 5)))
        targets = np.unique(starts[: max(1, starts.size - 1)])
        stop_at = int(rng.integers(-1, n))
        mask = np.zeros(n, bool)
        mask[targets] = True
        for rule in RULES:
            kw = {"starts": starts, "episode": episode, "stop_at": stop_at, "seed": checked, "rule": rule,
                  "max_executions": 10**6}
            try:
                whole = learn_model(succ, cost, target=mask, **kw)
            except RuntimeError:  # a walk that never reaches some target action within the cap: skipped alike
                continue
            assert LocalWorld(succ, cost).explore(targets, starts, episode, stop_at, checked, rule) == whole
        checked += 1


def test_a_local_world_refuses_what_is_not_a_list_of_states():
    world = LocalWorld(GridWorld(5, 1).next_state)
    for bad in (np.array([-1]), np.array([5]), np.array([], dtype=int), np.ones(5, bool)):
        with pytest.raises(ValueError, match="list of state indices"):
            world.explore(bad, np.array([0]), 2)
        with pytest.raises(ValueError, match="list of state indices"):
            world.explore(np.array([0]), bad, 2)
