"""The survival world of Ch. 4: grid, objects, sensors (Fig. 4.2) and the compiled step and sensing kernels.

See the package docstring (``connrl.envs.survival``) and docs/RECONSTRUCTION.md, "Survival world".
"""

from __future__ import annotations

import math

import numba
import numpy as np

# ------------------------------------------------------------------------------------------------ world
GRID_SIZE = 25
# R (docs/RECONSTRUCTION.md, "Survival world"): Lin 1992 Fig. 2 transcription, 8-fold symmetric;
# row 0 = north; "I" = agent start,
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
# (81, 16) table: coarse code of energy 0..80 (R: centres 0, 5, ..., 75, on when |E - 5k| < 7.5)
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


