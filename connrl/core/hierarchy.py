"""Hierarchical learning in a deterministic world, counted in action executions (thesis 6.2.2): single level.

Given the world's table ``succ`` and k subgoal (centre) states, with l the largest distance between neighbouring
centres:
1. each abstract action c is learnt in its vicinity: the reset operator places the agent at a random state within
   l steps of c (the application space), and the agent explores for at most l executions or until it reaches c;
   the action is learnt when every action of every application-space state has been tried (a shortest path from
   any of them to c stays inside, so the model there yields the optimal abstract action);
2. the abstract level is learnt by executing abstract actions between neighbouring centres (each costs its path
   length in executions) until every one has been tried from every centre.
Each phase explores with ``connrl.core.model_learning``: the abstract actions on the part of the table their short
episodes can reach (``LocalWorld``, exact), the abstract level with ``learn_model``. Resets cost nothing (6.2.2
counts executions). The flat learner is ``learn_model`` on the whole table (6.2.1).

``overhead`` measures what the hierarchy costs the policy: paths must pass through subgoals (6.2.2: "solution
paths found in this way may not be optimal").
"""

from __future__ import annotations

import heapq

import numba
import numpy as np

from connrl.core.model_learning import LocalWorld, explore, learn_model


@numba.njit(cache=True)
def ball(succ, source, radius):
    """States within ``radius`` steps of ``source`` and their distances (BFS over ``succ``; moves assumed
    reversible, as on grids, so these are also the distances *to* ``source``)."""
    n, n_actions = succ.shape
    dist = np.full(n, -1, dtype=np.int64)
    dist[source] = 0
    queue = np.empty(n, dtype=np.int64)
    queue[0] = source
    head, tail = 0, 1
    while head < tail:
        s = queue[head]
        head += 1
        if dist[s] == radius:
            continue
        for a in range(n_actions):
            t = succ[s, a]
            if t >= 0 and dist[t] < 0:
                dist[t] = dist[s] + 1
                queue[tail] = t
                tail += 1
    states = queue[:tail].copy()
    return states, dist[states]


def abstract_graph(succ: np.ndarray, centres: np.ndarray, l: int) -> tuple[np.ndarray, np.ndarray]:
    """The abstract level: from each centre, an abstract action to every other centre within ``l`` steps, costing
    that distance. Returns (succ, cost) tables over centre indices (-1 pads)."""
    where = {int(c): i for i, c in enumerate(centres)}
    edges = []
    for c in centres:
        states, dist = ball(succ, int(c), int(l))
        edges.append([(where[int(s)], int(d)) for s, d in zip(states, dist, strict=True) if int(s) in where
                      and int(s) != int(c)])
    width = max(1, max(len(e) for e in edges))
    a_succ, a_cost = np.full((len(centres), width), -1), np.ones((len(centres), width), dtype=np.int64)
    for i, e in enumerate(edges):
        for j, (t, d) in enumerate(e):
            a_succ[i, j], a_cost[i, j] = t, d
    return a_succ, a_cost


def single_level(succ: np.ndarray, centres: np.ndarray, l: int, seed: int = 0, rule: str = "greedy") -> dict:
    """Executions to learn the k abstract actions and then the abstract level (module docstring)."""
    rng = np.random.default_rng(seed)
    actions = 0
    world = LocalWorld(succ)
    for c in centres:
        states, _ = ball(world.succ, int(c), int(l))
        actions += world.explore(states, states, int(l), int(c), seed=int(rng.integers(2**31)), rule=rule)
    a_succ, a_cost = abstract_graph(succ, centres, l)
    level = learn_model(a_succ, cost=a_cost, seed=int(rng.integers(2**31)), rule=rule)
    return {"abstract_actions": actions, "abstract_level": level, "total": actions + level}


def overhead(succ: np.ndarray, centres: np.ndarray, l: int, goal: int, exact: np.ndarray) -> float:
    """Mean over states of (hierarchical path length) / (shortest path length): the agent takes the applicable
    abstract action that reaches a subgoal at the least cost (6.2.2), i.e. walks to its nearest centre (ties: the
    one with the shorter route on), then along the abstract level's shortest route to ``goal`` (a centre).
    ``exact``: true distances to ``goal``."""
    a_succ, a_cost = abstract_graph(succ, centres, l)
    g = int(np.flatnonzero(centres == goal)[0])
    far = np.full(len(centres), np.inf)  # abstract distance of each centre to the goal (Dijkstra; edges symmetric)
    far[g] = 0.0
    heap = [(0.0, g)]
    while heap:
        d, i = heapq.heappop(heap)
        if d > far[i]:
            continue
        for j, w in zip(a_succ[i], a_cost[i], strict=True):
            if j >= 0 and d + w < far[j]:
                far[j] = d + w
                heapq.heappush(heap, (d + w, int(j)))
    near = np.full(succ.shape[0], np.inf)  # distance to the nearest centre, and that centre's route on
    route = np.full(succ.shape[0], np.inf)
    for i, c in enumerate(centres):
        states, dist = ball(succ, int(c), int(l))
        nearer = (dist < near[states]) | ((dist == near[states]) & (dist + far[i] < route[states]))
        near[states[nearer]] = dist[nearer]
        route[states[nearer]] = dist[nearer] + far[i]
    away = exact > 0
    return float(np.mean(route[away] / exact[away]))


def multi_level(succ: np.ndarray, levels: list[np.ndarray], spacing: list[int], seed: int = 0,
                rule: str = "greedy") -> list[int]:
    """6.2.3: executions to learn every abstract action of every level; returns one count per level.

    ``levels[i]`` are the base states of level i's abstract space (``levels[0]``: every base state; each level a
    subset of the one below; the last holds only the goal), ``spacing[i]`` the base distance between neighbouring
    level-i states (``spacing[0]`` = 1). Level i's action to c is learnt on level i-1's graph (its abstract actions,
    each costing its path length) from resets to level-(i-1) states within ``spacing[i]`` of c, in episodes of at
    most ``spacing[i]`` executions; the last level's, to the goal, explores level h-1's whole space without resets
    (6.2.2's abstract level)."""
    rng = np.random.default_rng(seed)
    counts = []
    for i in range(1, len(levels)):
        if i == 1:
            world = LocalWorld(succ)
            index = np.arange(succ.shape[0])
        else:
            world = LocalWorld(*abstract_graph(succ, levels[i - 1], spacing[i - 1]))
            index = np.full(succ.shape[0], -1)
            index[levels[i - 1]] = np.arange(len(levels[i - 1]))
        top = i == len(levels) - 1
        count = 0
        for c in levels[i]:
            if top:
                count += explore(world.succ, world.cost, seed=int(rng.integers(2**31)), rule=rule)
                continue
            states, _ = ball(succ, int(c), int(spacing[i]))
            mine = index[states]
            mine = mine[mine >= 0]
            count += world.explore(mine, mine, int(spacing[i]), int(index[c]), seed=int(rng.integers(2**31)),
                                   rule=rule)
        counts.append(count)
    return counts
