"""The scripted teacher of the survival task (3.7, 4.3.1): it plays from the full state, in place of a person."""

from __future__ import annotations

from collections import deque

import numpy as np

from connrl.envs.survival.env import SurvivalEnv
from connrl.envs.survival.world import DIRECTIONS, GRID_SIZE, OBSTACLES


# ----------------------------------------------------------------------------------------------- teacher
def _grid_distance(sources: np.ndarray, limit: int) -> np.ndarray:
    """Obstacle-aware walking distance (capped at `limit`) from the nearest source cell to every cell."""
    free = ~OBSTACLES
    dist = np.full((GRID_SIZE, GRID_SIZE), limit, dtype=np.int64)
    dist[sources[:, 0], sources[:, 1]] = 0
    for _ in range(limit):  # Bellman-Ford relaxation by whole-grid shifts (cheap for small limits)
        best = dist.copy()
        np.minimum(best[1:], dist[:-1] + 1, out=best[1:])
        np.minimum(best[:-1], dist[1:] + 1, out=best[:-1])
        np.minimum(best[:, 1:], dist[:, :-1] + 1, out=best[:, 1:])
        np.minimum(best[:, :-1], dist[:, 1:] + 1, out=best[:, :-1])
        best[~free] = limit
        dist = best
    return dist


def _reachable(start: tuple[int, int], allowed: np.ndarray, max_depth: int) -> int:
    """How many `allowed` cells lie within `max_depth` steps of start (the room to escape into)."""
    seen, frontier = {start}, [start]
    for _ in range(max_depth):
        nxt = []
        for r, c in frontier:
            for dr, dc in DIRECTIONS:
                cell = (r + dr, c + dc)
                inside = 0 <= cell[0] < GRID_SIZE and 0 <= cell[1] < GRID_SIZE
                if inside and allowed[cell] and cell not in seen:
                    seen.add(cell)
                    nxt.append(cell)
        frontier = nxt
    return len(seen)


def scripted_teacher_action(env: SurvivalEnv, danger_radius: int = 2) -> int:
    """A good action for the current state, computed from the full (hidden) state: a scripted teacher.

    Walks the shortest path (BFS) to the nearest food through cells more than `danger_radius` steps
    (obstacle-aware walking distance) from every enemy. If no such path exists it retreats: it takes the
    move (bumping into an obstacle counts as staying) that maximises the distance to the nearest enemy,
    then the room left to escape into. Returned in ``env``'s action representation.
    """
    st = env.get_state()
    ar, ac = st["agent"]
    limit = 8
    enemy_dist = _grid_distance(st["enemies"], limit)
    safe = ~OBSTACLES & (enemy_dist > danger_radius)
    first: dict[tuple[int, int], int] = {}
    queue: deque[tuple[int, int]] = deque()
    for d, (dr, dc) in enumerate(DIRECTIONS):
        cell = (ar + dr, ac + dc)
        if 0 <= cell[0] < GRID_SIZE and 0 <= cell[1] < GRID_SIZE and safe[cell]:
            first[cell] = d
            queue.append(cell)
    target_dir = None
    while queue:  # BFS over safe cells, remembering each cell's first move
        r, c = queue.popleft()
        if st["food"][r, c]:
            target_dir = first[(r, c)]
            break
        for dr, dc in DIRECTIONS:
            cell = (r + dr, c + dc)
            if 0 <= cell[0] < GRID_SIZE and 0 <= cell[1] < GRID_SIZE and safe[cell] and cell not in first:
                first[cell] = first[(r, c)]
                queue.append(cell)
    if target_dir is None:  # no safe path to food: retreat
        best = None
        for d, (dr, dc) in enumerate(DIRECTIONS):
            r, c = ar + dr, ac + dc
            if not (0 <= r < GRID_SIZE and 0 <= c < GRID_SIZE) or OBSTACLES[r, c]:
                r, c = ar, ac  # a bump: the agent stays where it is
            score = (int(enemy_dist[r, c]), _reachable((r, c), enemy_dist > 1, 6))
            if best is None or score > best:
                best, target_dir = score, d
    if env.action_representation == "local":
        return (target_dir - st["orientation"]) % 4
    return int(target_dir)


def scripted_teacher_lesson(
    env: SurvivalEnv, seed: int | None = None, options: dict | None = None, max_steps: int = 1000
):
    """Play one whole play with :func:`scripted_teacher_action` and return it as a lesson.

    Returns a list of ``(obs, action, reward, next_obs, terminated, truncated)`` tuples (thesis 3.5: a
    lesson is the sequence of experiences of one play), plus the final ``info`` as a second value.
    """
    obs, info = env.reset(seed=seed, options=options)
    lesson = []
    for _ in range(max_steps):
        action = scripted_teacher_action(env)
        next_obs, reward, terminated, truncated, info = env.step(action)
        lesson.append((obs, action, reward, next_obs, terminated, truncated))
        obs = next_obs
        if terminated or truncated:
            break
    return lesson, info


