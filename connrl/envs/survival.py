"""Survival task of thesis Ch. 4: an agent collects food on a 25x25 grid while four enemies chase it.

Description
-----------
The 25x25 cell world of thesis 4.1 (SPEC.md section 2 reconstructs the lost Fig. 4.1 cell for cell). There
are four kinds of objects: the agent ("I"), food ("$"), enemies ("E") and obstacles ("O"). Each step the
agent walks to one of the four adjacent cells (into an obstacle: it stays put, a *collision*). Then each
enemy, in turn, stays with probability 0.2 or else moves with the probabilities of App. A.1: it favours
directions pointing at the agent, more strongly the closer the agent is (:func:`enemy_move_probabilities`).
The agent has two conflicting goals: eat as much food as possible and avoid the enemies. It sees only a
local area through three sensor arrays (food, enemy, obstacle), plus its energy level and a little history.

Action Space
------------
``Discrete(4)``. Indices run clockwise so that the two representations (4.2.3) share one numbering:

=====  =====================  ==========================================  ===
index  ``"global"``           ``"local"`` (relative to orientation)       key
=====  =====================  ==========================================  ===
0      north (row - 1)        front                                       w
1      east  (col + 1)        right                                       d
2      south (row + 1)        back                                        s
3      west  (col - 1)        left                                        a
=====  =====================  ==========================================  ===

``KEYMAP`` maps the keys above to action indices (the same for both representations); ``ACTION_NAMES``
names the actions of each representation. Under ``"local"`` the agent starts each play with a random
orientation and after every step faces the direction it tried to move in (even when it collided).

Observation Space
-----------------
``Box(-0.5, 0.5, (145,), float64)``; every unit is binary, -0.5 (off) or +0.5 (on) (5.3.2). Layout:

=========  =====  =============================================================================
slice      units  content
=========  =====  =============================================================================
0:52       52     food map: 12 "X" (plus, 5 cells) sensors at the cells with L1 distance 1-2, then 20
                  "O" (3x3, 9 cells) at the even-coordinate cells with L1 = 4 or 6, then 20 "Y"
                  (diamond L1 <= 2, 13 cells) at the even-coordinate cells with L1 = 10 (Fig. 4.2a)
52:84      32     enemy map: the same X and O sensors as units 0:32 of the food map (Fig. 4.2b)
84:124     40     obstacle map: one single-cell sensor per cell with L1 = 1..4; cells outside the
                  grid count as obstacles (Fig. 4.2c)
124:140    16     energy, coarse coded: unit k on when ``|E - 5k| < 7.5`` (E capped at 80, see below)
140:144    4      previous action, one-hot (all off at the start of a play)
144        1      the previous move collided with an obstacle
=========  =====  =============================================================================

Within each group sensors are ordered by type (X, O, Y) and then by (row, col) offset from the agent, row
first (``SENSOR_OFFSETS`` / ``SENSOR_TYPES`` list them). A sensor is on when any cell of its receptive field
holds the object. Under ``"global"`` the maps are in the world frame (up = north) and the history holds the
previous *world direction*; under ``"local"`` the maps are rotated so that up = the agent's front and the
history holds the previous *local* action.

Action symmetry (4.2.4). :func:`rotate_observation(obs, k) <rotate_observation>` returns the observation
the agent would get if the whole world were rotated by ``k * 90`` degrees **counter-clockwise** (north
becomes west); it permutes the map units and rotates the previous-action one-hot with them (energy and
the collision bit are unchanged). A "global" agent with ONE network valued for moving north evaluates
"move in direction d" as ``net(rotate_observation(obs, ACTION_ROTATION[d]))``; ``ACTION_ROTATION = (0, 1, 2,
3)`` because rotating the world by ``d`` quarter turns counter-clockwise turns direction ``d`` into north.
All three arrays are invariant under quarter turns, so this is a permutation of units.

Rewards
-------
-1.0 when the agent dies (caught by an enemy or energy 0), +0.4 when it eats food, 0.0 otherwise (4.2.1).
Death takes precedence: eating food and dying in the same step gives -1.0.

Starting State
--------------
Agent at (18, 12); enemies at (1, 12), (6, 6), (6, 12), (6, 18); 15 food pieces on distinct random free
cells (not obstacles, not the agent's or enemies' cells); energy 40; no previous action. Under ``"local"``
a uniformly random initial orientation.

Episode End
-----------
Terminated when the agent has eaten all the food, or it dies: it moves onto an enemy, an enemy moves onto
it, or its energy reaches 0. Truncated (a timeout is not a failure) after ``max_steps`` steps if given.
``info["outcome"]`` is then ``"all_food"``, ``"killed"``, ``"starved"`` or ``"timeout"`` (``None`` during a
play). Energy bounds a play (40 + 15 * 15 = 265 moves at most), so no time limit is needed.

Arguments
---------
``gymnasium.make("connrl/Survival-v0", action_representation="global", render_mode=None, max_steps=None)``

* ``action_representation``: ``"global"`` (Study 1, 4.3.2) or ``"local"`` (Study 2, 4.3.3).
* ``render_mode``: ``None``, ``"ansi"`` (text grid, like Fig. 4.1) or ``"rgb_array"`` (a picture with an
  energy bar and a legend).
* ``max_steps``: optional step limit per play (truncation).

Seeding and environment sets (4.3.1). ``reset(seed=s)`` seeds ``np_random``; the food placement, the local
orientation and all enemy moves then come from it, so a play is reproducible. ``reset(options=
{"layout_seed": k})`` places the food from ``numpy.random.default_rng(k)`` instead (enemy moves and
orientation still come from ``np_random``), so an *environment* (a food layout) can be replayed many times
with different dynamics. :func:`environment_sets` draws the 300 training and 50 test layout seeds of one
experiment from one seed. ``options={"food": [(row, col), ...]}`` places food by hand (taught lessons).

Hooks for agents. :meth:`SurvivalEnv.get_state` / :meth:`SurvivalEnv.set_state` copy the full simulator
state (the "perfect" action model of 4.2.5 steps a copy; by default the copy does not carry the random
generator, so the model samples its own enemy moves). ``info`` always has ``position`` (row, col),
``energy``, ``food_eaten``, ``food_left``, ``orientation`` (0..3 = N, E, S, W), ``collided``, ``steps`` and
``outcome``. :func:`scripted_teacher_action` / :func:`scripted_teacher_lesson` play from the full state
(BFS to the nearest food through cells away from enemies, else retreat) to produce taught lessons (3.7);
on 100 random environments the teacher eats 13.3 of 15 pieces on average and clears 65% of them.
:func:`make_taught_lessons` builds the two shipped lessons (``connrl/data/lessons/survival-global.json``,
``survival-local.json``, written with ``connrl.replay.save_lessons``) from plays where it ate all the food.
:func:`render_rgb` draws any state from :meth:`SurvivalEnv.get_state`.

Differences from the thesis
---------------------------
* The grid, the sensor layouts and the energy code are SPEC.md reconstructions (R) of lost figures; the
  figures' numbers (25x25, 145 = 52 + 32 + 40 + 16 + 5 inputs, 5/9/13-cell receptive fields) are kept.
* App. A.1 does not say how angle and distance are measured; we use Euclidean geometry on cell centres
  (``dist = hypot(drow, dcol)``, ``angle`` = the unsigned angle between the action's direction and the
  enemy-to-agent vector, in degrees). ``T(dist)`` is used exactly as printed, including its jump at 4.
* The thesis does not say whether enemies may share a cell or stand on food; here they may do both (food
  is never eaten by enemies). An enemy with no free neighbour stays.
* Energy above 82 would switch every energy unit of SPEC's code off; the code saturates instead
  (energy is capped at 80 *for the code only*; the real energy is not capped).
* The order within a step (move, eat, check contact / all food / starvation, then enemies move one by one)
  is not spelled out in the thesis; when the last piece of food is eaten the play ends before enemies move.
"""

from __future__ import annotations

import math
from collections import deque
from functools import lru_cache
from typing import Any

import gymnasium as gym
import numba
import numpy as np
from gymnasium import spaces

# ------------------------------------------------------------------------------------------------ world
GRID_SIZE = 25
# SPEC.md section 2 (R): Lin 1992 Fig. 2 transcription, 8-fold symmetric; row 0 = north; "I" = agent start,
# "E" = enemy starts. Only "O" matters for the grid itself.
GRID_MAP = (
    "OOOOOO.............OOOOOO",
    "O...........E...........O",
    "O..OO...OO.OOO.OO...OO..O",
    "O.OOO...OO.O.O.OO...OOO.O",
    "O.OOO...............OOO.O",
    "O.......................O",
    "......E.....E.....E......",
    ".........................",
    "..OO....OOOO.OOOO....OO..",
    "..OO....OOO...OOO....OO..",
    "........OO.....OO........",
    "..OO....O.......O....OO..",
    "..O.........O.........O..",
    "..OO....O.......O....OO..",
    "........OO.....OO........",
    "..OO....OOO...OOO....OO..",
    "..OO....OOOO.OOOO....OO..",
    ".........................",
    "............I............",
    "O.......................O",
    "O.OOO...............OOO.O",
    "O.OOO...OO.O.O.OO...OOO.O",
    "O..OO...OO.OOO.OO...OO..O",
    "O.......................O",
    "OOOOOO.............OOOOOO",
)
OBSTACLES = np.array([[ch == "O" for ch in row] for row in GRID_MAP], dtype=bool)
AGENT_START = (18, 12)
ENEMY_STARTS = ((1, 12), (6, 6), (6, 12), (6, 18))
N_FOOD = 15  # 4.1
START_ENERGY = 40  # 4.1
FOOD_ENERGY = 15  # 4.1
MOVE_COST = 1  # 4.1
ENEMY_STAY_PROB = 0.2  # App. A.1: enemies move at 80% of the agent's speed
REWARD_DEATH, REWARD_FOOD = -1.0, 0.4  # 4.2.1

# Directions, clockwise: 0 = north, 1 = east, 2 = south, 3 = west, as (drow, dcol).
DIRECTIONS = np.array([(-1, 0), (0, 1), (1, 0), (0, -1)], dtype=np.int64)
ACTION_NAMES = {"global": ("north", "east", "south", "west"), "local": ("front", "right", "back", "left")}
KEYMAP = {"w": 0, "d": 1, "s": 2, "a": 3}  # same indices under both representations (see docstring)
ACTION_ROTATION = (0, 1, 2, 3)  # quarter turns (counter-clockwise) that make global action d point north
OUTCOMES = (None, "all_food", "killed", "starved", "timeout")
_ALL_FOOD, _KILLED, _STARVED, _TIMEOUT = 1, 2, 3, 4

# ---------------------------------------------------------------------------------------------- sensors
# (drow, dcol) offsets relative to the agent, sorted row-major within each sensor type.
_RF = {  # receptive field of each sensor type (4.2.2): X 5 cells, O 9 cells, Y 13 cells
    "X": [(a, b) for a in range(-1, 2) for b in range(-1, 2) if abs(a) + abs(b) <= 1],
    "O": [(a, b) for a in range(-1, 2) for b in range(-1, 2)],
    "Y": [(a, b) for a in range(-2, 3) for b in range(-2, 3) if abs(a) + abs(b) <= 2],
    "o": [(0, 0)],  # obstacle sensors see one cell
}


def _ring(l1_values, even_only):
    cells = [(a, b) for a in range(-12, 13) for b in range(-12, 13) if abs(a) + abs(b) in l1_values]
    return [(a, b) for a, b in cells if not even_only or (a % 2 == 0 and b % 2 == 0)]


_X, _O, _Y = _ring((1, 2), False), _ring((4, 6), True), _ring((10,), True)
SENSOR_OFFSETS = {
    "food": np.array(_X + _O + _Y, dtype=np.int64),
    "enemy": np.array(_X + _O, dtype=np.int64),
    "obstacle": np.array(_ring((1, 2, 3, 4), False), dtype=np.int64),
}
SENSOR_TYPES = {
    "food": "X" * len(_X) + "O" * len(_O) + "Y" * len(_Y),
    "enemy": "X" * len(_X) + "O" * len(_O),
    "obstacle": "o" * 40,
}
N_ENERGY_UNITS, N_HISTORY_UNITS = 16, 5
OBS_SLICES = {
    "food": slice(0, 52),
    "enemy": slice(52, 84),
    "obstacle": slice(84, 124),
    "energy": slice(124, 140),
    "history": slice(140, 145),
}
N_INPUTS = 145
assert [len(SENSOR_OFFSETS[k]) for k in ("food", "enemy", "obstacle")] == [52, 32, 40]

_PAD = 12  # farthest cell any sensor sees: Y sensor at L1 10 plus its radius 2
_W = GRID_SIZE + 2 * _PAD  # width of the padded grids the kernels index with flat offsets
_MAX_CODED_ENERGY = 80
# (81, 16) table: coarse code of energy 0..80 (SPEC (R): centres 0, 5, ..., 75, on when |E - 5k| < 7.5)
_ENERGY_CODE = np.where(
    np.abs(np.arange(_MAX_CODED_ENERGY + 1)[:, None] - 5.0 * np.arange(N_ENERGY_UNITS)[None, :]) < 7.5,
    0.5,
    -0.5,
)


def _rot_ccw(offsets: np.ndarray, k: int) -> np.ndarray:
    """Rotate (drow, dcol) offsets by k quarter turns counter-clockwise (row axis points south)."""
    out = np.array(offsets, dtype=np.int64)
    for _ in range(k % 4):
        out = np.stack([-out[..., 1], out[..., 0]], axis=-1)
    return out


def _field_table(kind: str, orientation: int) -> np.ndarray:
    """Flat padded-grid offsets of every cell of every sensor's receptive field, for an agent facing
    `orientation` (sensors rotate with a "local" agent). Shorter fields repeat their first cell."""
    centres = _rot_ccw(SENSOR_OFFSETS[kind], -orientation)  # local frame -> world frame: turn clockwise
    width = max(len(_RF[t]) for t in SENSOR_TYPES[kind])
    table = np.empty((len(centres), width), dtype=np.int64)
    for i, (c, t) in enumerate(zip(centres, SENSOR_TYPES[kind], strict=True)):
        cells = [(c[0] + a, c[1] + b) for a, b in _RF[t]]  # RFs are rotation invariant
        cells += [cells[0]] * (width - len(cells))
        table[i] = [a * _W + b for a, b in cells]
    return table


_FOOD_TABLE = np.stack([_field_table("food", o) for o in range(4)])  # (4, 52, 13)
_ENEMY_TABLE = np.stack([_field_table("enemy", o) for o in range(4)])  # (4, 32, 9)
_OBST_TABLE = np.stack([_field_table("obstacle", o)[:, 0] for o in range(4)])  # (4, 40)
_OBST_PAD = np.ones((_W, _W), dtype=np.uint8)
_OBST_PAD[_PAD:-_PAD, _PAD:-_PAD] = OBSTACLES


def _rotation_permutations() -> np.ndarray:
    perms = np.empty((4, N_INPUTS), dtype=np.int64)
    for k in range(4):
        perm = np.arange(N_INPUTS)
        for kind in ("food", "enemy", "obstacle"):
            offsets, types, base = SENSOR_OFFSETS[kind], SENSOR_TYPES[kind], OBS_SLICES[kind].start
            index = {(t, int(a), int(b)): i for i, ((a, b), t) in enumerate(zip(offsets, types, strict=True))}
            # new unit at offset v reads the old unit at offset R^-k v (fields are rotation invariant)
            source = _rot_ccw(offsets, -k)
            perm[base : base + len(offsets)] = [
                base + index[(t, int(a), int(b))] for (a, b), t in zip(source, types, strict=True)
            ]
        h = OBS_SLICES["history"].start
        perm[h : h + 4] = h + (np.arange(4) + k) % 4  # previous direction d becomes d - k
        perms[k] = perm
    return perms


ROTATION_PERMUTATIONS = _rotation_permutations()


def rotate_observation(obs: np.ndarray, k: int) -> np.ndarray:
    """Observation seen if the whole world were rotated by ``k * 90`` degrees counter-clockwise.

    Pure function on a (..., 145) array; returns a new array. Map units are permuted, the previous-action
    one-hot is rotated with them (a previous move north becomes west for k = 1), energy and the collision
    bit are kept. For a "global" agent, the value of action d is ``net(rotate_observation(obs,
    ACTION_ROTATION[d]))`` (4.2.4).
    """
    obs = np.asarray(obs)
    if obs.shape[-1] != N_INPUTS:
        raise ValueError(
            f"rotate_observation expects observations with {N_INPUTS} units, got shape {obs.shape}"
        )
    return obs[..., ROTATION_PERMUTATIONS[int(k) % 4]]


# ----------------------------------------------------------------------------------------------- kernels
@numba.njit(cache=True)
def _enemy_probs(obst_pad, er, ec, ar, ac, out):
    """App. A.1: P(move i | enemy moves) for i = 0 east, 1 south, 2 west, 3 north, into out[0:4]."""
    dx, dy = float(ac - ec), float(er - ar)  # enemy -> agent vector, x east, y north
    dist = math.hypot(dx, dy)
    if dist <= 4.0:
        t = 15.0 - dist
    elif dist <= 15.0:
        t = 9.0 - dist / 2.0
    else:
        t = 1.0
    total = 0.0
    for i in range(4):
        ux, uy = (1.0, 0.0) if i == 0 else (0.0, -1.0) if i == 1 else (-1.0, 0.0) if i == 2 else (0.0, 1.0)
        rr, cc = er - int(uy), ec + int(ux)
        if obst_pad[rr + 12, cc + 12]:  # _PAD
            out[i] = 0.0
            continue
        if dist == 0.0:
            angle = 0.0
        else:  # unsigned angle in degrees between (ux, uy) and (dx, dy)
            angle = math.degrees(math.atan2(abs(ux * dy - uy * dx), ux * dx + uy * dy))
        w = (180.0 - abs(angle)) / 180.0
        out[i] = math.exp(0.33 * w * t)
        total += out[i]
    for i in range(4):
        out[i] = out[i] / total if total > 0.0 else 0.0
    return total > 0.0


@numba.njit(cache=True)
def _step_kernel(obst_pad, food_pad, enemy_pad, enemies, agent, s, direction, u):
    """Advance the world one step. s = [energy, orientation, prev_action, collided, eaten, food_left,
    steps, outcome]. Returns the reward; s[7] gets the outcome code (0 = play goes on)."""
    p = 12  # _PAD
    r, c = agent[0], agent[1]
    dr = -1 if direction == 0 else 1 if direction == 2 else 0
    dc = 1 if direction == 1 else -1 if direction == 3 else 0
    if obst_pad[r + dr + p, c + dc + p]:
        s[3] = 1
    else:
        s[3] = 0
        r += dr
        c += dc
    agent[0], agent[1] = r, c
    s[0] -= 1
    s[6] += 1
    ate = food_pad[r + p, c + p] != 0
    if ate:
        food_pad[r + p, c + p] = 0
        s[0] += 15  # FOOD_ENERGY
        s[4] += 1
        s[5] -= 1
    if enemy_pad[r + p, c + p] > 0:
        s[7] = 2
    elif s[5] == 0:
        s[7] = 1
    elif s[0] <= 0:
        s[7] = 3
    else:
        probs = np.empty(4)
        for i in range(enemies.shape[0]):
            if u[2 * i] < 0.2:  # ENEMY_STAY_PROB
                continue
            if not _enemy_probs(obst_pad, enemies[i, 0], enemies[i, 1], r, c, probs):
                continue
            x, k = u[2 * i + 1], 0
            while k < 3 and x >= probs[k]:
                x -= probs[k]
                k += 1
            while probs[k] == 0.0:  # float round-off at the top end: take the last possible move
                k -= 1
            er, ec = enemies[i, 0], enemies[i, 1]
            enemy_pad[er + p, ec + p] -= 1
            er += 1 if k == 1 else -1 if k == 3 else 0
            ec += 1 if k == 0 else -1 if k == 2 else 0
            enemies[i, 0], enemies[i, 1] = er, ec
            enemy_pad[er + p, ec + p] += 1
            if er == r and ec == c:
                s[7] = 2
                break
    if s[7] == 2 or s[7] == 3:
        return -1.0  # REWARD_DEATH
    return 0.4 if ate else 0.0  # REWARD_FOOD


@numba.njit(cache=True)
def _observe_kernel(
    obst_pad, food_pad, enemy_pad, agent, s, local, food_t, enemy_t, obst_t, energy_code, out
):
    p, w = 12, 49  # _PAD, _W
    centre = (agent[0] + p) * w + agent[1] + p
    o = s[1] if local else 0
    f, e, b = food_pad.ravel(), enemy_pad.ravel(), obst_pad.ravel()
    for i in range(food_t.shape[1]):
        on = False
        for j in range(food_t.shape[2]):
            if f[centre + food_t[o, i, j]]:
                on = True
                break
        out[i] = 0.5 if on else -0.5
    for i in range(enemy_t.shape[1]):
        on = False
        for j in range(enemy_t.shape[2]):
            if e[centre + enemy_t[o, i, j]]:
                on = True
                break
        out[52 + i] = 0.5 if on else -0.5
    for i in range(obst_t.shape[1]):
        out[84 + i] = 0.5 if b[centre + obst_t[o, i]] else -0.5
    energy = min(max(s[0], 0), 80)
    for k in range(16):
        out[124 + k] = energy_code[energy, k]
    for k in range(4):
        out[140 + k] = 0.5 if s[2] == k else -0.5
    out[144] = 0.5 if s[3] else -0.5


assert (_PAD, _W) == (12, 49)  # the kernels hard-code _PAD and _W as literals


def enemy_move_probabilities(enemy: tuple[int, int], agent: tuple[int, int]) -> dict[str, float]:
    """Probabilities of an enemy's next move on the standard grid (App. A.1), including the 20% stay.

    Returns ``{"stay", "east", "south", "west", "north"}`` -> probability (summing to 1).
    """
    probs = np.zeros(4)
    moves = _enemy_probs(_OBST_PAD, int(enemy[0]), int(enemy[1]), int(agent[0]), int(agent[1]), probs)
    if not moves:
        return {"stay": 1.0, "east": 0.0, "south": 0.0, "west": 0.0, "north": 0.0}
    move = 1.0 - ENEMY_STAY_PROB
    return {"stay": ENEMY_STAY_PROB} | {
        n: move * float(q) for n, q in zip(("east", "south", "west", "north"), probs, strict=True)
    }


def environment_sets(seed: int, n_train: int = 300, n_test: int = 50) -> tuple[list[int], list[int]]:
    """Layout seeds of the training and test environments of one experiment (4.3.1), all distinct.

    Play environment ``k`` with ``env.reset(seed=..., options={"layout_seed": k})``.
    """
    if n_train < 0 or n_test < 0:
        raise ValueError(f"n_train and n_test must be >= 0, got {n_train}, {n_test}")
    seeds = np.random.default_rng(seed).choice(2**31 - 1, size=n_train + n_test, replace=False)
    return [int(x) for x in seeds[:n_train]], [int(x) for x in seeds[n_train:]]


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
        if not self.action_space.contains(action):
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


# -------------------------------------------------------------------------------------------- rgb render
_CELL = 20
_COLORS = {
    "floor": (242, 238, 226),
    "line": (222, 216, 200),
    "obstacle": (70, 74, 86),
    "food": (226, 160, 20),
    "enemy": (200, 30, 40),
    "agent": (30, 90, 220),
    "text": (25, 25, 25),
    "bar_bg": (215, 215, 215),
    "panel": (255, 255, 255),
}


@lru_cache(maxsize=1)
def _glyphs() -> tuple[dict[str, np.ndarray], int, int]:
    """Alpha masks of printable ASCII in a monospace font, rendered once with matplotlib's Agg."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    chars = "".join(chr(i) for i in range(32, 127))
    cw, ch, dpi = 8, 15, 100
    fig = Figure(figsize=(cw * len(chars) / dpi, ch / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    for i, x in enumerate(chars):
        fig.text(
            i * cw / (cw * len(chars)), 4 / ch, x, family="DejaVu Sans Mono", fontsize=9.5, color="black"
        )
    canvas.draw()
    alpha = 255 - np.asarray(canvas.buffer_rgba())[:, :, 0].astype(np.int16)
    masks = {x: (alpha[:, i * cw : (i + 1) * cw] / 255.0).astype(np.float32) for i, x in enumerate(chars)}
    return masks, cw, ch


def _draw_text(img: np.ndarray, text: str, row: int, col: int, color=(25, 25, 25)) -> None:
    masks, cw, ch = _glyphs()
    for i, x in enumerate(text):
        m = masks.get(x)
        c0 = col + i * cw
        if m is None or c0 + cw > img.shape[1]:
            continue
        region = img[row : row + ch, c0 : c0 + cw].astype(np.float32)
        img[row : row + ch, c0 : c0 + cw] = (
            region * (1 - m[..., None]) + np.array(color) * m[..., None]
        ).astype(np.uint8)


@lru_cache(maxsize=1)
def _shape_masks() -> dict[str, np.ndarray]:
    """Per-cell masks: food = small disc, enemy = diamond, agent = disc."""
    y, x = np.mgrid[0:_CELL, 0:_CELL] + 0.5 - _CELL / 2
    return {
        "food": (x**2 + y**2) <= (0.28 * _CELL) ** 2,
        "enemy": (np.abs(x) + np.abs(y)) <= 0.47 * _CELL,
        "agent": (x**2 + y**2) <= (0.45 * _CELL) ** 2,
        "arrow": (y <= 0.22 * _CELL) & (np.abs(x) <= (y + 0.36 * _CELL) * 0.5),  # points north
    }


@lru_cache(maxsize=1)
def _background() -> np.ndarray:
    g = GRID_SIZE * _CELL
    margin, panel = 8, 64
    img = np.full((g + 2 * margin + panel, g + 2 * margin, 3), _COLORS["panel"], dtype=np.uint8)
    board = np.full((g, g, 3), _COLORS["floor"], dtype=np.uint8)
    board[::_CELL, :] = _COLORS["line"]
    board[:, ::_CELL] = _COLORS["line"]
    for r, c in np.argwhere(OBSTACLES):
        board[r * _CELL : (r + 1) * _CELL, c * _CELL : (c + 1) * _CELL] = _COLORS["obstacle"]
    img[margin : margin + g, margin : margin + g] = board
    # legend (last line of the panel)
    legend_row = margin + g + 42
    col = margin
    masks = _shape_masks()
    for name, label in (
        ("agent", "agent (I)"),
        ("enemy", "enemy (E)"),
        ("food", "food ($)"),
        ("obstacle", "obstacle (O)"),
    ):
        cell = img[legend_row - 2 : legend_row - 2 + _CELL, col : col + _CELL]
        if name == "obstacle":
            cell[:] = _COLORS["obstacle"]
        else:
            cell[masks[name]] = _COLORS[name]
        _draw_text(img, label, legend_row + 1, col + _CELL + 4)
        col += _CELL + 4 + 8 * len(label) + 16
    return img


def render_rgb(state: dict[str, Any], action_representation: str = "global") -> np.ndarray:
    """Picture of a state (from :meth:`SurvivalEnv.get_state`), in the spirit of thesis Fig. 4.1."""
    img = _background().copy()
    margin, g = 8, GRID_SIZE * _CELL
    masks = _shape_masks()

    def paint(r, c, mask, color):
        cell = img[
            margin + r * _CELL : margin + (r + 1) * _CELL, margin + c * _CELL : margin + (c + 1) * _CELL
        ]
        cell[mask] = color

    for r, c in np.argwhere(state["food"]):
        paint(r, c, masks["food"], _COLORS["food"])
    ar, ac = state["agent"]
    paint(ar, ac, masks["agent"], _COLORS["agent"])
    if action_representation == "local" or state.get("prev_action", -1) >= 0:
        heading = state["orientation"] if action_representation == "local" else state["prev_action"]
        paint(ar, ac, np.rot90(masks["arrow"], -heading), (255, 255, 255))  # arrow: facing / last move
    for r, c in state["enemies"]:
        paint(r, c, masks["enemy"], _COLORS["enemy"])
    if state.get("outcome") == "killed":
        cell = img[
            margin + ar * _CELL : margin + (ar + 1) * _CELL, margin + ac * _CELL : margin + (ac + 1) * _CELL
        ]
        d = np.arange(_CELL)
        for off in (-1, 0, 1):
            cell[d, np.clip(d + off, 0, _CELL - 1)] = (0, 0, 0)
            cell[d, np.clip(_CELL - 1 - d + off, 0, _CELL - 1)] = (0, 0, 0)
    # energy bar: 4 px per unit, a tick every 15 units (one food)
    energy = int(state["energy"])
    top = margin + g + 8
    _draw_text(img, f"energy {energy:3d}", top, margin)
    x0, width = margin + 96, g - 96
    img[top + 1 : top + 13, x0 : x0 + width] = _COLORS["bar_bg"]
    fill = min(width, 4 * max(energy, 0))
    bar_color = (200, 40, 40) if energy <= 10 else (230, 160, 20) if energy <= 25 else (40, 160, 70)
    img[top + 1 : top + 13, x0 : x0 + fill] = bar_color
    img[top + 1 : top + 13, x0 : x0 + width : 60] = (255, 255, 255)
    eaten, left = int(state["food_eaten"]), int(np.sum(state["food"]))
    status = f"food {eaten}/{eaten + left}   step {int(state['steps'])}"
    if state.get("outcome"):
        status += f"   [{state['outcome']}]"
    _draw_text(img, status, top + 17, margin)
    return img


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


def make_taught_lessons(action_representation: str = "global", n_lessons: int = 2, seed: int = 0):
    """Taught lessons (3.7, 4.3.1) played by :func:`scripted_teacher_lesson`, as ``connrl.replay.Lesson``.

    Like the thesis's teacher, who "got all the food in each of the lessons", we keep only plays in which
    the teacher eats all 15 pieces: layout seeds 0, 1, 2, ... (play seed = `seed` + layout seed) are tried
    in order and the first `n_lessons` complete plays are returned. Each lesson's ``meta`` records the
    layout seed, the play seed and the food cells, so the play can be re-run exactly.
    """
    from connrl.replay import Lesson  # lazy: the env does not depend on the replay machinery

    env = SurvivalEnv(action_representation=action_representation)
    lessons = []
    for layout_seed in range(1000):
        options = {"layout_seed": layout_seed}
        env.reset(seed=seed + layout_seed, options=options)
        food_cells = np.argwhere(env.get_state()["food"]).tolist()
        steps, info = scripted_teacher_lesson(env, seed=seed + layout_seed, options=options)
        if info["outcome"] != "all_food":
            continue
        meta = {
            "teacher": "scripted_teacher_action(danger_radius=2)",
            "action_representation": action_representation,
            "layout_seed": layout_seed,
            "play_seed": seed + layout_seed,
            "food": food_cells,
            "food_eaten": info["food_eaten"],
            "outcome": info["outcome"],
        }
        lessons.append(Lesson.from_steps(steps, taught=True, meta=meta))
        if len(lessons) == n_lessons:
            return lessons
    raise RuntimeError(f"the scripted teacher completed fewer than {n_lessons} of 1000 environments")
