"""Hand-built survival states for the env tests."""

import numpy as np

import connrl.envs  # noqa: F401  (registers connrl/Survival-v0)
from connrl.envs.survival import (
    GRID_SIZE,
    OBSTACLES,
)


def make_state(agent, enemies=((1, 12),) * 4, food=(), energy=40, prev_action=-1, collided=False,
               orientation=0):
    grid = np.zeros((GRID_SIZE, GRID_SIZE), dtype=bool)
    for r, c in food:
        grid[r, c] = True
    return {"agent": agent, "enemies": np.array(enemies), "food": grid, "energy": energy,
            "orientation": orientation, "prev_action": prev_action, "collided": collided, "outcome": None,
            "done": False}


def obs_of(env, state):
    env.set_state(state)
    return env.observe()


def free(r, c):
    return 0 <= r < GRID_SIZE and 0 <= c < GRID_SIZE and not OBSTACLES[r, c]
