"""``GridWorld``: the deterministic d-dimensional grid worlds of thesis 6.2's complexity analysis.

Description:
    ``side ** dim`` states on a grid; ``2 * dim`` actions, a step of +-1 along one axis; a step off the grid
    leaves the state where it is (the walls). Deterministic and discrete, as 6.2 assumes. The world is a table
    (``next_state[s, a]``), so learners can count action executions without a simulator in the loop.

Regions (6.2.2): ``regions(block)`` cuts the grid into cubes of ``block`` states a side (the last ones smaller
where ``side`` is not a multiple); each region's centre state is its geometric centre (footnote 2).

Differences from the thesis: none in the world; the thesis does not give side lengths or region shapes beyond
"approximately equal size and shape".
"""

from __future__ import annotations

from collections import deque

import numpy as np


class GridWorld:
    """A deterministic grid of ``side ** dim`` states (see the module docstring)."""

    def __init__(self, side: int, dim: int = 2):
        if int(side) != side or side < 2:
            raise ValueError(f"side must be an integer >= 2, got {side!r}")
        if dim not in (1, 2, 3):
            raise ValueError(f"dim must be 1, 2 or 3, got {dim!r}")
        self.side, self.dim = int(side), int(dim)
        self.n = self.side ** self.dim
        self.n_actions = 2 * self.dim
        self.coords = np.stack(np.unravel_index(np.arange(self.n), (self.side,) * self.dim), axis=1)
        nxt = np.empty((self.n, self.n_actions), dtype=np.int64)
        for a in range(self.n_actions):
            axis, step = divmod(a, 2)
            c = self.coords.copy()
            c[:, axis] = np.clip(c[:, axis] + (1 if step == 0 else -1), 0, self.side - 1)
            nxt[:, a] = np.ravel_multi_index(tuple(c.T), (self.side,) * self.dim)
        self.next_state = nxt

    def index(self, coords) -> int:
        return int(np.ravel_multi_index(tuple(int(c) for c in coords), (self.side,) * self.dim))

    def distances_to(self, goal: int) -> np.ndarray:
        """Exact shortest-path distances (action executions) from every state to ``goal`` (BFS; the grid's moves
        are reversible, so distances to and from a state agree)."""
        dist = np.full(self.n, -1, dtype=np.int64)
        dist[goal] = 0
        queue = deque([goal])
        while queue:
            s = queue.popleft()
            for t in self.next_state[s]:
                if dist[t] < 0:
                    dist[t] = dist[s] + 1
                    queue.append(t)
        return dist

    def regions(self, block: int) -> tuple[np.ndarray, np.ndarray]:
        """(region of each state, centre state of each region) for cubes of ``block`` states a side."""
        if int(block) != block or not 1 <= block <= self.side:
            raise ValueError(f"block must be an integer in 1..{self.side}, got {block!r}")
        per_axis = -(-self.side // block)
        cell = self.coords // block
        region = np.ravel_multi_index(tuple(cell.T), (per_axis,) * self.dim)
        centres = np.empty(per_axis ** self.dim, dtype=np.int64)
        for r in range(centres.size):
            lo = np.array(np.unravel_index(r, (per_axis,) * self.dim)) * block
            hi = np.minimum(lo + block, self.side) - 1
            centres[r] = self.index((lo + hi) // 2)
        return region, centres

    def nested_centres(self, factor: int, levels: int) -> list[np.ndarray]:
        """6.2.3's abstraction hierarchy on a grid whose side is ``factor ** levels`` (``factor`` odd): level i's
        states are the centres of cubes ``factor ** i`` a side, so each level's are a subset of the one below; the
        last level is the single centre of the whole grid (the goal). ``[all states, level 1, ..., level h]``."""
        if factor < 3 or factor % 2 == 0 or self.side != factor ** levels:
            raise ValueError(f"nested_centres needs an odd factor >= 3 and side = factor ** levels, got factor "
                             f"{factor}, levels {levels}, side {self.side}")
        out = [np.arange(self.n)]
        for i in range(1, levels + 1):
            b = factor ** i
            on = np.all(self.coords % b == (b - 1) // 2, axis=1)
            out.append(np.flatnonzero(on))
        return out
