"""``SurvivalEnv``: the Gymnasium environment of Ch. 4 (see the package docstring)."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from connrl.envs.survival.render import render_rgb
from connrl.envs.survival.world import (
    _ENEMY_TABLE,
    _ENERGY_CODE,
    _FOOD_TABLE,
    _OBST_PAD,
    _OBST_TABLE,
    _PAD,
    _TIMEOUT,
    _W,
    ACTION_NAMES,
    AGENT_START,
    ENEMY_STARTS,
    GRID_SIZE,
    N_FOOD,
    N_INPUTS,
    OBSTACLES,
    OUTCOMES,
    START_ENERGY,
    _observe_kernel,
    _step_kernel,
)


# --------------------------------------------------------------------------------------------------- env
class SurvivalEnv(gym.Env):
    """The survival task of thesis Ch. 4 (see the module docstring for the full description)."""

    metadata = {"render_modes": ["ansi", "rgb_array"], "render_fps": 8}

    def __init__(
        self,
        action_representation: str = "global",
        render_mode: str | None = None,
        max_steps: int | None = None,
    ):
        if action_representation not in ("global", "local"):
            raise ValueError(
                f"action_representation must be 'global' or 'local', got {action_representation!r}"
            )
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None, 'ansi' or 'rgb_array', got {render_mode!r}")
        if max_steps is not None and (not isinstance(max_steps, int | np.integer) or max_steps < 1):
            raise ValueError(f"max_steps must be None or a positive int, got {max_steps!r}")
        self.action_representation = action_representation
        self.render_mode = render_mode
        self.max_steps = None if max_steps is None else int(max_steps)
        self.action_space = spaces.Discrete(4)
        self.observation_space = spaces.Box(-0.5, 0.5, (N_INPUTS,), np.float64)
        self._local = action_representation == "local"
        self._food = np.zeros((_W, _W), dtype=np.uint8)
        self._enemy_count = np.zeros((_W, _W), dtype=np.uint8)
        self._enemies = np.array(ENEMY_STARTS, dtype=np.int64)
        self._agent = np.array(AGENT_START, dtype=np.int64)
        self._s = np.zeros(
            8, dtype=np.int64
        )  # energy, orientation, prev, collided, eaten, left, steps, outcome
        self._s[2] = -1
        self._done = True

    # -------------------------------------------------------------------------------------------- core
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = set(options) - {"layout_seed", "food"}
        if unknown:
            raise ValueError(f"unknown reset options {sorted(unknown)}; allowed: 'layout_seed', 'food'")
        if "layout_seed" in options and "food" in options:
            raise ValueError("give either options['layout_seed'] or options['food'], not both")
        self._agent[:] = AGENT_START
        self._enemies[:] = ENEMY_STARTS
        if "food" in options:
            food = self._check_food(options["food"])
        else:
            layout_seed = options.get("layout_seed")
            rng = self.np_random if layout_seed is None else np.random.default_rng(layout_seed)
            free = _free_start_cells()
            food = free[rng.choice(len(free), size=N_FOOD, replace=False)]
        orientation = int(self.np_random.integers(4)) if self._local else 0
        self._food[:] = 0
        self._food[food[:, 0] + _PAD, food[:, 1] + _PAD] = 1
        self._sync_enemy_count()
        self._s[:] = (START_ENERGY, orientation, -1, 0, 0, len(food), 0, 0)
        self._done = False
        return self._observe(), self._info()

    def step(self, action):
        if self._done:
            raise RuntimeError("the play has ended (or reset() was never called); call reset() first")
        # a plain int in range needs no Gymnasium check (it costs more than the step itself)
        if not (action.__class__ is int and 0 <= action < 4) and not self.action_space.contains(action):
            raise ValueError(
                f"action must be an int in 0..3 ({ACTION_NAMES[self.action_representation]}), got {action!r}"
            )
        action = int(action)
        direction = (int(self._s[1]) + action) % 4 if self._local else action
        u = self.np_random.random(2 * len(self._enemies))
        reward = _step_kernel(
            _OBST_PAD, self._food, self._enemy_count, self._enemies, self._agent, self._s, direction, u
        )
        self._s[2] = action  # history: local action under "local", world direction under "global"
        if self._local:
            self._s[1] = direction
        terminated = self._s[7] != 0
        truncated = not terminated and self.max_steps is not None and self._s[6] >= self.max_steps
        if truncated:
            self._s[7] = _TIMEOUT
        self._done = terminated or truncated
        return self._observe(), float(reward), bool(terminated), bool(truncated), self._info()

    def _observe(self) -> np.ndarray:
        out = np.empty(N_INPUTS)
        _observe_kernel(
            _OBST_PAD,
            self._food,
            self._enemy_count,
            self._agent,
            self._s,
            self._local,
            _FOOD_TABLE,
            _ENEMY_TABLE,
            _OBST_TABLE,
            _ENERGY_CODE,
            out,
        )
        return out

    def _info(self) -> dict[str, Any]:
        s = self._s
        return {
            "position": (int(self._agent[0]), int(self._agent[1])),
            "energy": int(s[0]),
            "food_eaten": int(s[4]),
            "food_left": int(s[5]),
            "orientation": int(s[1]),
            "collided": bool(s[3]),
            "steps": int(s[6]),
            "outcome": OUTCOMES[int(s[7])],
        }

    def _sync_enemy_count(self):
        self._enemy_count[:] = 0
        np.add.at(self._enemy_count, (self._enemies[:, 0] + _PAD, self._enemies[:, 1] + _PAD), 1)

    @staticmethod
    def _check_food(food) -> np.ndarray:
        cells = np.asarray(food, dtype=np.int64).reshape(-1, 2) if len(food) else np.zeros((0, 2), np.int64)
        if len(cells) < 1:
            raise ValueError("options['food'] must list at least one (row, col) cell")
        if len({tuple(x) for x in cells}) != len(cells):
            raise ValueError(f"options['food'] has repeated cells: {cells.tolist()}")
        occupied = {AGENT_START, *ENEMY_STARTS}
        for r, c in cells:
            if not (0 <= r < GRID_SIZE and 0 <= c < GRID_SIZE) or OBSTACLES[r, c] or (r, c) in occupied:
                raise ValueError(
                    f"food cell {(int(r), int(c))} is outside the grid, an obstacle, or a start cell"
                )
        return cells

    # ------------------------------------------------------------------------------------------ hooks
    def get_state(self, include_rng: bool = False) -> dict[str, Any]:
        """Deep copy of the simulator state (plain ints and arrays in world coordinates).

        Keys: agent (row, col), enemies (4, 2), food (25, 25) bool, energy, orientation, prev_action (-1 =
        none), collided, food_eaten, steps, outcome, done; with ``include_rng`` also ``rng`` (the
        bit-generator state), so that ``set_state`` replays the very same future enemy moves.
        """
        s = self._s
        state = {
            "agent": (int(self._agent[0]), int(self._agent[1])),
            "enemies": self._enemies.copy(),
            "food": self._food[_PAD:-_PAD, _PAD:-_PAD].astype(bool),
            "energy": int(s[0]),
            "orientation": int(s[1]),
            "prev_action": int(s[2]),
            "collided": bool(s[3]),
            "food_eaten": int(s[4]),
            "steps": int(s[6]),
            "outcome": OUTCOMES[int(s[7])],
            "done": bool(self._done),
        }
        if include_rng:
            import copy

            state["rng"] = copy.deepcopy(self.np_random.bit_generator.state)
        return state

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore a state from :meth:`get_state` (or a hand-built one with its keys; ``rng`` optional)."""
        missing = {"agent", "enemies", "food", "energy"} - set(state)
        if missing:
            raise ValueError(f"state is missing keys {sorted(missing)}")
        food = np.asarray(state["food"], dtype=bool)
        enemies = np.asarray(state["enemies"], dtype=np.int64)
        agent = tuple(int(x) for x in state["agent"])
        if food.shape != (GRID_SIZE, GRID_SIZE):
            raise ValueError(
                f"state['food'] must be a ({GRID_SIZE}, {GRID_SIZE}) bool array, got {food.shape}"
            )
        if enemies.ndim != 2 or enemies.shape[1] != 2:
            raise ValueError(f"state['enemies'] must have shape (n, 2), got {enemies.shape}")
        for name, (r, c) in [("agent", agent)] + [("enemy", tuple(e)) for e in enemies]:
            if not (0 <= r < GRID_SIZE and 0 <= c < GRID_SIZE) or OBSTACLES[r, c]:
                raise ValueError(f"{name} cell {(int(r), int(c))} is outside the grid or an obstacle")
        if (food & OBSTACLES).any():
            raise ValueError("state['food'] has food on obstacle cells")
        outcome = state.get("outcome")
        if outcome not in OUTCOMES:
            raise ValueError(f"state['outcome'] must be one of {OUTCOMES}, got {outcome!r}")
        self._agent[:] = agent
        self._enemies = enemies.copy()
        self._food[:] = 0
        self._food[_PAD:-_PAD, _PAD:-_PAD] = food
        self._sync_enemy_count()
        self._s[:] = (
            int(state["energy"]),
            int(state.get("orientation", 0)),
            int(state.get("prev_action", -1)),
            int(bool(state.get("collided", False))),
            int(state.get("food_eaten", 0)),
            int(food.sum()),
            int(state.get("steps", 0)),
            OUTCOMES.index(outcome),
        )
        self._done = bool(state.get("done", outcome is not None))
        if "rng" in state:
            self.np_random.bit_generator.state = state["rng"]

    def _snapshot(self) -> tuple:
        """The simulator's own arrays, copied: ``_restore`` puts them back as ``set_state`` would (a model that
        simulates several actions from one state sets it once, then restores it; the random stream is not kept)."""
        return (self._agent.copy(), self._enemies.copy(), self._food.copy(), self._enemy_count.copy(),
                self._s.copy(), self._done)

    def _restore(self, snapshot: tuple) -> None:
        agent, enemies, food, count, s, done = snapshot
        self._agent[:], self._food[:], self._enemy_count[:], self._s[:] = agent, food, count, s
        self._enemies, self._done = enemies.copy(), done

    def observe(self) -> np.ndarray:
        """The current observation (as returned by the last reset/step, recomputed)."""
        return self._observe()

    def info(self) -> dict[str, Any]:
        """The current info dict (as returned by the last reset/step)."""
        return self._info()

    # ----------------------------------------------------------------------------------------- render
    def render(self):
        if self.render_mode == "ansi":
            return self._render_ansi()
        if self.render_mode == "rgb_array":
            return render_rgb(self.get_state(), self.action_representation)
        return None

    def _render_ansi(self) -> str:
        st = self.get_state()
        rows = [["O" if o else "." for o in row] for row in OBSTACLES]
        for r, c in np.argwhere(st["food"]):
            rows[r][c] = "$"
        for r, c in st["enemies"]:
            rows[r][c] = "E"
        ar, ac = st["agent"]
        rows[ar][ac] = "^>v<"[st["orientation"]] if self._local else "I"
        if st["outcome"] == "killed":
            rows[ar][ac] = "X"
        lines = ["   " + "".join(str(c % 10) for c in range(GRID_SIZE))]
        lines += [f"{r:2d} " + "".join(row) for r, row in enumerate(rows)]
        energy = st["energy"]
        lines.append(f"energy {energy:3d} " + "H" * min(energy // 5, 40))
        status = f"food {st['food_eaten']}/{st['food_eaten'] + int(st['food'].sum())}  step {st['steps']}"
        if st["outcome"]:
            status += f"  [{st['outcome']}]"
        lines.append(status)
        lines.append("I/^>v< agent  E enemy  $ food  O obstacle")
        return "\n".join(lines) + "\n"


@lru_cache(maxsize=1)
def _free_start_cells() -> np.ndarray:
    occupied = np.zeros_like(OBSTACLES)
    for r, c in (AGENT_START, *ENEMY_STARTS):
        occupied[r, c] = True
    return np.argwhere(~OBSTACLES & ~occupied)


