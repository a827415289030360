"""Learning a complete model of a deterministic world by exploration, counting action executions (thesis 6.2.1).

6.2's complexity analysis counts the action executions an agent needs before it knows every transition it must
know; the optimal policy then follows by planning on the model, which costs no executions. The exploration rule
here is greedy mapping, a Koenig-style rule (6.2.1 cites Koenig's real-time search): go by the shortest known
route to the nearest state with an untried action, try it, repeat. Its worst case is O(b n) executions for b
state-action pairs and n states; on grids it is far below that.

The world is a table: ``succ[s, a]`` the next state (-1: no such action), ``cost[s, a]`` the executions one use of
the action takes (1 for base actions; a path length for abstract actions, 6.2.2). With ``episode`` > 0 the agent
works in episodes of at most that many executions, each from a reset state (6.2.2's reset operator), ending early at
``stop_at`` ("until the abstract state is reached or else after l steps"). Learning ends when every action of every
``target`` state has been tried. Pure given ``seed`` (compiled with Numba; ``learn_model`` checks its inputs).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def _nearest_untried(known, tried, target, pos, budget, cost, dist, parent, queue, touched):
    """BFS over known transitions from ``pos``: the nearest target state (in moves) with an untried action whose
    route plus the action fits ``budget`` (< 0: no limit). Returns the state, or -1; ``dist`` holds route costs,
    ``parent`` the route (kept for inspection; the count needs only ``dist``). ``dist`` is -1 except at the
    ``touched[0]`` states first in ``queue`` (the last call's search), which are reset here: a search costs what it
    visits, not n (O(n^2) over a run otherwise)."""
    n_actions = known.shape[1]
    for i in range(touched[0]):
        dist[queue[i]] = -1
    dist[pos] = 0
    parent[pos] = -1
    head, tail = 0, 1
    queue[0] = pos
    while head < tail:
        s = queue[head]
        head += 1
        if target[s]:
            for a in range(n_actions):
                if not tried[s, a] and (budget < 0 or dist[s] + cost[s, a] <= budget):
                    touched[0] = tail
                    return s
        for a in range(n_actions):
            t = known[s, a]
            if t >= 0 and dist[t] < 0 and (budget < 0 or dist[s] + cost[s, a] <= budget):
                dist[t] = dist[s] + cost[s, a]
                parent[t] = s
                queue[tail] = t
                tail += 1
    touched[0] = tail
    return -1


@numba.njit(cache=True)
def _learn(succ, cost, target, starts, episode, stop_at, seed, max_executions, rule):
    np.random.seed(seed)
    n, n_actions = succ.shape
    known = np.full((n, n_actions), -1, dtype=np.int64)
    tried = succ < 0  # absent actions count as tried
    remaining = 0
    for s in range(n):
        if target[s]:
            for a in range(n_actions):
                if not tried[s, a]:
                    remaining += 1
    dist = np.full(n, -1, dtype=np.int64)
    parent = np.empty(n, dtype=np.int64)
    queue = np.empty(n, dtype=np.int64)
    touched = np.zeros(1, dtype=np.int64)
    total = 0
    pos = starts[np.random.randint(starts.size)]
    while remaining > 0 and total < max_executions:
        if episode > 0:
            pos = starts[np.random.randint(starts.size)]  # the reset operator
        spent = 0
        while remaining > 0 and total < max_executions:
            if episode > 0 and (spent >= episode or (pos == stop_at and spent > 0)):
                break
            if rule == 1:  # random walk: a random action where the agent stands
                u = pos
                a = np.random.randint(n_actions)
                if succ[u, a] < 0:
                    continue  # no such action here (an abstract level's padding): draw again
                if episode > 0 and spent + cost[u, a] > episode:
                    break
                if target[u] and not tried[u, a]:
                    remaining -= 1
                tried[u, a] = True
                known[u, a] = succ[u, a]
                spent += cost[u, a]
                total += cost[u, a]
                pos = succ[u, a]
                continue
            u = _nearest_untried(known, tried, target, pos, episode - spent if episode > 0 else -1, cost, dist,
                                 parent, queue, touched)
            if u < 0:
                break
            spent += dist[u]
            total += dist[u]
            a = 0
            while tried[u, a]:
                a += 1
            tried[u, a] = True
            known[u, a] = succ[u, a]
            remaining -= 1
            spent += cost[u, a]
            total += cost[u, a]
            pos = succ[u, a]
        if episode <= 0:
            break
    return total, remaining


RULES = ("greedy", "random")


def check_world(succ: np.ndarray, cost: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``succ`` and ``cost`` (default: 1 everywhere) as contiguous int64 tables, checked; a loop exploring one
    table many times (``connrl.core.hierarchy``) checks it once and calls ``explore``."""
    succ = np.ascontiguousarray(succ, dtype=np.int64)
    if succ.ndim != 2 or succ.shape[0] < 1 or (succ >= succ.shape[0]).any():
        raise ValueError(f"succ must be an (n, actions) table of next states in -1..n-1, got shape {succ.shape}")
    cost = np.ones_like(succ) if cost is None else np.ascontiguousarray(cost, dtype=np.int64)
    if cost.shape != succ.shape or (cost[succ >= 0] < 1).any():
        raise ValueError("cost must have succ's shape and be >= 1 wherever an action exists")
    return succ, cost


def explore(succ: np.ndarray, cost: np.ndarray, target: np.ndarray | None = None, starts: np.ndarray | None = None,
            episode: int = 0, stop_at: int = -1, seed: int = 0, max_executions: int = 10**12,
            rule: str = "greedy") -> int:
    """``learn_model`` on tables ``check_world`` returned."""
    if rule not in RULES:
        raise ValueError(f"rule must be one of {RULES}, got {rule!r}")
    n = succ.shape[0]
    target = np.ones(n, dtype=np.bool_) if target is None else np.ascontiguousarray(target, dtype=np.bool_)
    starts = np.arange(n) if starts is None else np.ascontiguousarray(starts, dtype=np.int64)
    if target.shape != (n,) or starts.size == 0 or not ((starts >= 0) & (starts < n)).all():
        raise ValueError("target must be one bool per state and starts a non-empty list of states")
    if episode > 0 and ((succ[target] >= 0) & (cost[target] > episode)).any():
        raise ValueError(f"a target action costs more than a whole episode's {episode} executions: it can never be "
                         "tried")
    total, remaining = _learn(succ, cost, target, starts, int(episode), int(stop_at), int(seed), int(max_executions),
                              RULES.index(rule))
    if remaining:
        raise RuntimeError(f"{remaining} target actions still untried after {total} executions")
    return int(total)


@numba.njit(cache=True)
def _within_budget(succ, cost, starts, budget, dist, queued, queue, found):
    """The states within ``budget`` (summed cost) of any start, in the order first reached (a label-correcting
    search: with costs above 1 a state's label can drop after it was expanded, and it is expanded again).
    ``dist`` (n,) must be -1 and ``queued`` False everywhere, and are left so; ``queue``, ``found``: n of scratch."""
    n = succ.shape[0]
    m = head = tail = count = 0  # queue: a ring of n entries, each state in it at most once
    for s in starts:
        if dist[s] < 0:
            dist[s], queued[s], found[m], queue[tail] = 0, True, s, s
            m, tail, count = m + 1, (tail + 1) % n, count + 1
    while count > 0:
        s = queue[head]
        head, count, queued[s] = (head + 1) % n, count - 1, False
        for a in range(succ.shape[1]):
            t = succ[s, a]
            if t < 0 or dist[s] + cost[s, a] > budget or (dist[t] >= 0 and dist[s] + cost[s, a] >= dist[t]):
                continue
            if dist[t] < 0:
                found[m] = t
                m += 1
            dist[t] = dist[s] + cost[s, a]
            if not queued[t]:
                queued[t], queue[tail] = True, t
                tail, count = (tail + 1) % n, count + 1
    out = found[:m].copy()
    for s in out:
        dist[s] = -1
    return out


class LocalWorld:
    """One table explored many times in short episodes (6.2.2's abstract actions): each ``explore`` runs on the
    part of the table its episodes can reach, so a run costs what it visits, not the table's size.

    Exact: with episodes of at most ``episode`` executions from ``starts``, every state the agent stands on lies
    within ``episode`` of a start, so it acts and plans only there; an action leading out of that part leads to one
    extra state with no actions, which keeps the action present (so it is drawn, and found too dear, exactly as on
    the whole table) and untried. ``tests/core/test_model_learning.py`` compares the counts with ``explore``'s."""

    def __init__(self, succ: np.ndarray, cost: np.ndarray | None = None):
        self.succ, self.cost = check_world(succ, cost)
        n = self.succ.shape[0]
        self._dist, self._queued = np.full(n, -1, dtype=np.int64), np.zeros(n, dtype=np.bool_)
        self._queue, self._found = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
        self._index = np.full(n, -1, dtype=np.int64)

    def explore(self, target_states: np.ndarray, starts: np.ndarray, episode: int, stop_at: int = -1,
                seed: int = 0, rule: str = "greedy") -> int:
        """``explore`` on the whole table with ``target`` the states listed in ``target_states`` (indices, not a
        mask), from episodes of ``episode`` >= 1."""
        if episode < 1:
            raise ValueError(f"episode must be >= 1 (short episodes are what make a world local), got {episode}")
        n = self.succ.shape[0]
        for name, states in (("starts", starts), ("target_states", target_states)):
            states = np.asarray(states)
            if states.dtype == np.bool_ or states.ndim != 1 or states.size == 0 or not (
                    np.issubdtype(states.dtype, np.integer) and ((states >= 0) & (states < n)).all()):
                raise ValueError(f"{name} must be a non-empty list of state indices in 0..{n - 1}")
        starts = np.ascontiguousarray(starts, dtype=np.int64)
        part = _within_budget(self.succ, self.cost, starts, int(episode), self._dist, self._queued, self._queue,
                              self._found)
        m = part.size
        self._index[part] = np.arange(m)
        try:
            rows = self.succ[part]
            local = np.where(rows >= 0, self._index[np.maximum(rows, 0)], -1)
            local[(rows >= 0) & (local < 0)] = m  # out of reach: the extra state
            succ = np.vstack([local, np.full((1, rows.shape[1]), -1, dtype=np.int64)])
            cost = np.vstack([self.cost[part], np.ones((1, rows.shape[1]), dtype=np.int64)])
            mine = self._index[np.asarray(target_states, dtype=np.int64)]
            if (mine < 0).any():
                raise ValueError(f"target states out of reach of the starts within {episode} executions")
            target = np.zeros(m + 1, dtype=np.bool_)
            target[mine] = True
            inside = self._index[stop_at] if 0 <= stop_at < self._index.size else -1
            return explore(succ, cost, target, self._index[starts], episode, int(inside), seed, rule=rule)
        finally:
            self._index[part] = -1


def learn_model(succ: np.ndarray, cost: np.ndarray | None = None, target: np.ndarray | None = None,
                starts: np.ndarray | None = None, episode: int = 0, stop_at: int = -1, seed: int = 0,
                max_executions: int = 10**12, rule: str = "greedy") -> int:
    """Action executions until every action of every ``target`` state (default: all) has been tried, starting from
    a random state of ``starts`` (default: all), in episodes of ``episode`` executions from reset states when
    ``episode`` > 0. ``rule``: "greedy" mapping (module docstring) or a "random" walk (each step a uniformly random
    action, an uninformed explorer for comparison)."""
    return explore(*check_world(succ, cost), target, starts, episode, stop_at, seed, max_executions, rule)


def greedy_mapping_reference(succ: np.ndarray, start: int) -> int:
    """Greedy mapping read top to bottom (``learn_model`` from one start, every action of every state, unit costs,
    no episodes): a fresh BFS over known transitions for every try, the first untried action by index. The compiled
    ``_learn`` is its fast path; tests compare the two over whole runs, benchmarks/bench_recharge.py times them."""
    if (succ < 0).any():
        raise ValueError("the reference takes tables where every action exists (no -1 entries)")
    n, n_actions = succ.shape
    known, tried, pos, total = {}, set(), start, 0
    while len(tried) < n * n_actions:
        dist, queue, head = {pos: 0}, [pos], 0
        while True:
            if head == len(queue):
                raise ValueError(f"{n * n_actions - len(tried)} actions cannot be reached from state {start}")
            s = queue[head]
            head += 1
            untried = [a for a in range(n_actions) if (s, a) not in tried]
            if untried:
                break
            for a in range(n_actions):
                t = known[s, a]
                if t not in dist:
                    dist[t] = dist[s] + 1
                    queue.append(t)
        tried.add((s, untried[0]))
        known[s, untried[0]] = int(succ[s, untried[0]])
        total += dist[s] + 1
        pos = known[s, untried[0]]
    return total

