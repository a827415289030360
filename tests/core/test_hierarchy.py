"""Single-level hierarchical learning (6.2.2) counted in executions: the abstract level's graph, the costs on a tiny
line by hand, the path overhead of going through subgoals."""

import numpy as np

from connrl.core.hierarchy import abstract_graph, ball, multi_level, overhead, single_level
from connrl.core.model_learning import learn_model
from connrl.envs.grid import GridWorld


def test_ball_and_abstract_graph_on_a_line():
    g = GridWorld(9, 1)
    states, dist = ball(g.next_state, 4, 2)
    assert sorted(zip(states.tolist(), dist.tolist(), strict=True)) == [(2, 2), (3, 1), (4, 0), (5, 1), (6, 2)]
    _, centres = g.regions(3)  # 1, 4, 7
    a_succ, a_cost = abstract_graph(g.next_state, centres, 3)
    # each centre reaches its neighbours 3 steps away; the end ones have one neighbour
    assert [sorted(t for t in row if t >= 0) for row in a_succ] == [[1], [0, 2], [1]]
    assert a_cost[a_succ >= 0].tolist() == [3, 3, 3, 3]


def test_single_level_costs_add_up_from_their_parts():
    g = GridWorld(9, 1)
    _, centres = g.regions(3)
    h = single_level(g.next_state, centres, 3, seed=4)
    assert h["total"] == h["abstract_actions"] + h["abstract_level"]
    a_succ, a_cost = abstract_graph(g.next_state, centres, 3)
    # the abstract level: 4 abstract actions of 3 executions each, at least once each
    assert h["abstract_level"] >= 4 * 3 and h["abstract_level"] % 3 == 0
    assert h["abstract_actions"] >= 2 * 9  # every action of every application-space state tried at least once


def test_hierarchy_pays_off_for_a_random_walker_on_a_long_line():
    g = GridWorld(1000, 1)
    _, centres = g.regions(5)
    flat = learn_model(g.next_state, seed=0, rule="random")
    hier = single_level(g.next_state, centres, 5, seed=0, rule="random")["total"]
    assert hier < flat / 2  # a walk's n^2 cover time is confined to small regions


def test_overhead_of_paths_through_subgoals():
    g = GridWorld(9, 1)
    _, centres = g.regions(3)  # 1, 4, 7
    goal = 1
    exact = g.distances_to(goal)
    # nearest centre first: states 2 and 3 walk to 1 and 4 (3 goes away from the goal: 1 + 3 = 4 steps, not 2);
    # 5-8 walk to 4 or 7 then back along the centres; 0 walks to 1
    routes = {0: 1, 2: 1, 3: 1 + 3, 4: 3, 5: 1 + 3, 6: 1 + 6, 7: 6, 8: 1 + 6}
    want = np.mean([routes[s] / exact[s] for s in routes])
    assert np.isclose(overhead(g.next_state, centres, 3, goal, exact), want)
    assert np.isclose(overhead(g.next_state, np.arange(9), 1, goal, exact), 1.0)  # every state a subgoal: none


def test_two_level_multi_level_is_the_single_level():
    """With one abstract level under the goal, Eq. 6.1's sum is 6.2.2's single level (same draws, same counts)."""
    g = GridWorld(9, 1)
    levels = g.nested_centres(3, 2)  # every state; 1, 4, 7; 4
    assert [lv.tolist() for lv in levels[1:]] == [[1, 4, 7], [4]]
    for rule in ("greedy", "random"):
        counts = multi_level(g.next_state, levels, [1, 3, 9], seed=2, rule=rule)
        single = single_level(g.next_state, levels[1], 3, seed=2, rule=rule)
        assert counts == [single["abstract_actions"], single["abstract_level"]]
