"""Survival world (thesis 4.1-4.2; docs/RECONSTRUCTION.md, "Survival world"): the grid and sensors against the
reconstruction's drawings, receptive fields, energy code, rotation symmetry (4.2.4), App. A.1's enemy moves."""

import math

import numpy as np
import pytest

from connrl.envs.survival import (
    ACTION_ROTATION,
    AGENT_START,
    ENEMY_STARTS,
    GRID_SIZE,
    OBS_SLICES,
    OBSTACLES,
    SENSOR_OFFSETS,
    SENSOR_TYPES,
    SurvivalEnv,
    enemy_move_probabilities,
    rotate_observation,
)
from tests.envs.survival_scenes import free, make_state, obs_of

# The reconstructed grid (docs/RECONSTRUCTION.md, "Survival world"; "I" = the agent start, "E" = enemy starts)
# and the sensor-array drawings of the project's reconstruction notes, copied verbatim.
GRID_DRAWING = """
OOOOOO.............OOOOOO
O...........E...........O
O..OO...OO.OOO.OO...OO..O
O.OOO...OO.O.O.OO...OOO.O
O.OOO...............OOO.O
O.......................O
......E.....E.....E......
.........................
..OO....OOOO.OOOO....OO..
..OO....OOO...OOO....OO..
........OO.....OO........
..OO....O.......O....OO..
..O.........O.........O..
..OO....O.......O....OO..
........OO.....OO........
..OO....OOO...OOO....OO..
..OO....OOOO.OOOO....OO..
.........................
............I............
O.......................O
O.OOO...............OOO.O
O.OOO...OO.O.O.OO...OOO.O
O..OO...OO.OOO.OO...OO..O
O.......................O
OOOOOO.............OOOOOO
"""


# The food drawing shows rows -10..+2 of a 21x21 map.
FOOD_DRAWING = """
..........Y..........
.....................
........Y...Y........
.....................
......Y...O...Y......
.....................
....Y...O.O.O...Y....
.....................
..Y...O.O.X.O.O...Y..
.........XXX.........
Y...O.O.XXIXX.O.O...Y
.........XXX.........
..Y...O.O.X.O.O...Y..
"""


ENEMY_DRAWING = """
......O......
.............
....O.O.O....
.............
..O.O.X.O.O..
.....XXX.....
O.O.XXIXX.O.O
.....XXX.....
..O.O.X.O.O..
.............
....O.O.O....
.............
......O......
"""


OBSTACLE_DRAWING = """
....o....
...ooo...
..ooooo..
.ooooooo.
ooooIoooo
.ooooooo.
..ooooo..
...ooo...
....o....
"""


# receptive fields as the notes define the letters: X plus (5 cells), O 3x3 (9), Y diamond (13), o one cell
FIELDS = {
    "X": lambda a, b: abs(a) + abs(b) <= 1,
    "O": lambda a, b: max(abs(a), abs(b)) <= 1,
    "Y": lambda a, b: abs(a) + abs(b) <= 2,
    "o": lambda a, b: a == 0 and b == 0,
}


def parse_drawing(text):
    """{(letter, drow, dcol)} of a drawing, and the range of rows it shows (relative to the agent)."""
    rows = text.strip().splitlines()
    (ci, cj), = [(i, row.index("I")) for i, row in enumerate(rows) if "I" in row]
    sensors = {(ch, i - ci, j - cj) for i, row in enumerate(rows) for j, ch in enumerate(row) if ch in "XOYo"}
    return sensors, (-ci, len(rows) - 1 - ci)


def env_sensors(kind):
    return {(t, int(a), int(b)) for (a, b), t in zip(SENSOR_OFFSETS[kind], SENSOR_TYPES[kind], strict=True)}


def rotate_set(sensors, k):
    out = set(sensors)
    for _ in range(k):
        out = {(t, -b, a) for t, a, b in out}
    return out


@pytest.fixture(scope="module")
def env():
    e = SurvivalEnv()
    e.reset(seed=0)
    return e


def test_grid_is_spec_grid_and_8_fold_symmetric():
    rows = GRID_DRAWING.strip().splitlines()
    assert OBSTACLES.shape == (25, 25) and len(rows) == 25
    assert (OBSTACLES == np.array([[ch == "O" for ch in row] for row in rows])).all()
    assert rows[AGENT_START[0]][AGENT_START[1]] == "I"
    assert all(rows[r][c] == "E" for r, c in ENEMY_STARTS)
    for k in range(4):
        assert (np.rot90(OBSTACLES, k) == OBSTACLES).all()
        assert (np.rot90(OBSTACLES, k).T == OBSTACLES).all()


# ------------------------------------------------------------------------------------------- sensors
@pytest.mark.parametrize("kind,drawing", [("food", FOOD_DRAWING), ("enemy", ENEMY_DRAWING),
                                          ("obstacle", OBSTACLE_DRAWING)])
def test_sensor_layout_matches_spec_drawing(kind, drawing):
    drawn, (top, bottom) = parse_drawing(drawing)
    ours = env_sensors(kind)
    assert {s for s in ours if top <= s[1] <= bottom} == drawn  # exactly the rows the drawing shows
    completed = set().union(*(rotate_set(drawn, k) for k in range(4)))  # the arrays are rotation invariant (4.2.4)
    assert ours == completed
    for k in range(4):
        assert rotate_set(ours, k) == ours


def _placement(v):
    """An agent cell p with p and p + v both free (so an object can sit at offset v), or None."""
    for r, c in np.argwhere(~OBSTACLES):
        if free(r + v[0], c + v[1]):
            return int(r), int(c)
    return None


@pytest.mark.parametrize("kind", ["food", "enemy"])
def test_receptive_fields_through_observations(env, kind):
    """One object at every offset within reach: each sensor is on iff the object is in its field."""
    sl = OBS_SLICES[kind]
    centres, types = SENSOR_OFFSETS[kind], SENSOR_TYPES[kind]
    reach = 12 if kind == "food" else 8
    for a in range(-reach, reach + 1):
        for b in range(-reach, reach + 1):
            p = _placement((a, b))
            if (a, b) == (0, 0) or p is None:
                continue
            obj = (p[0] + a, p[1] + b)
            state = make_state(p, food=[obj]) if kind == "food" else make_state(p, enemies=[obj] * 4)
            got = obs_of(env, state)[sl] > 0
            want = [FIELDS[t](a - c[0], b - c[1]) for c, t in zip(centres, types, strict=True)]
            assert got.tolist() == want, (kind, (a, b), p)


def test_obstacle_sensors_see_cells_and_the_outside(env):
    for p in [(18, 12), (0, 6), (6, 0), (12, 1), (23, 23), (1, 1), (12, 11)]:
        got = obs_of(env, make_state(p, enemies=[(1, 12)] * 4))[OBS_SLICES["obstacle"]] > 0
        want = [not free(p[0] + a, p[1] + b) for a, b in SENSOR_OFFSETS["obstacle"]]
        assert got.tolist() == want, p


def test_energy_coarse_code(env):
    def units(e):
        return np.flatnonzero(obs_of(env, make_state((18, 12), energy=e))[OBS_SLICES["energy"]] > 0).tolist()

    assert units(40) == [7, 8, 9]  # centres 35, 40, 45: |40 - 5k| < 7.5
    assert units(42) == [7, 8, 9]
    assert units(38) == [7, 8, 9]
    assert units(1) == [0, 1]
    assert units(80) == [15]
    assert units(200) == [15]  # saturates (see "Differences from the thesis")


# ----------------------------------------------------------------------------------------- symmetry
def _rotate_cell(r, c):  # a quarter turn counter-clockwise of the 25x25 world (north -> west)
    return GRID_SIZE - 1 - c, r


def _random_state(rng):
    cells = np.argwhere(~OBSTACLES)
    pick = cells[rng.choice(len(cells), size=20, replace=False)]
    cells = [tuple(int(v) for v in x) for x in pick]
    return make_state(cells[0], enemies=cells[1:5], food=cells[5:],
                      energy=int(rng.integers(1, 120)), prev_action=int(rng.integers(-1, 4)),
                      collided=bool(rng.integers(2)))


def _rotate_state(state):
    out = dict(state)
    out["agent"] = _rotate_cell(*state["agent"])
    out["enemies"] = np.array([_rotate_cell(r, c) for r, c in state["enemies"]])
    out["food"] = np.rot90(state["food"])
    out["orientation"] = (state["orientation"] - 1) % 4
    if state["prev_action"] >= 0:
        out["prev_action"] = (state["prev_action"] - 1) % 4  # a move north becomes a move west
    return out


def test_rotating_the_world_equals_rotate_observation(env):
    rng = np.random.default_rng(0)
    assert ACTION_ROTATION == (0, 1, 2, 3)
    for _ in range(50):
        state = _random_state(rng)
        obs = obs_of(env, state)
        rotated = state
        for k in range(1, 5):
            rotated = _rotate_state(rotated)
            assert np.array_equal(obs_of(env, rotated), rotate_observation(obs, k)), k
    batch = np.stack([obs, -obs])
    assert np.array_equal(rotate_observation(batch, 1)[1], rotate_observation(-obs, 1))


def test_action_symmetry_rotation_points_each_action_north(env):
    """rotate_observation(obs, ACTION_ROTATION[d]) shows the world with direction d pointing north."""
    for d, (dr, dc) in enumerate([(-1, 0), (0, 1), (1, 0), (0, -1)]):
        obs = obs_of(env, make_state((18, 12), food=[(18 + dr, 12 + dc)]))
        north_only = obs_of(env, make_state((18, 12), food=[(17, 12)]))
        assert np.array_equal(rotate_observation(obs, ACTION_ROTATION[d])[:52], north_only[:52])


def test_local_sensors_rotate_with_the_agent():
    glob, loc = SurvivalEnv(), SurvivalEnv(action_representation="local")
    glob.reset(seed=0)
    loc.reset(seed=0)
    rng = np.random.default_rng(1)
    for _ in range(20):
        state = _random_state(rng)
        for o in range(4):
            state["orientation"] = o
            maps = slice(0, 124)
            # facing direction o, the agent sees the world turned so that o is "up"
            assert np.array_equal(obs_of(loc, state)[maps], rotate_observation(obs_of(glob, state), o)[maps])
            # rotating world and agent together changes nothing for a local agent
            assert np.array_equal(obs_of(loc, _rotate_state(state))[maps], obs_of(loc, state)[maps])


# ------------------------------------------------------------------------------------------ dynamics
def test_enemy_probabilities_app_a1_hand_cases():
    # agent 3 cells east: dist 3 -> T = 15 - 3 = 12; W = 1 (east), 0.5 (north/south), 0 (west)
    p = enemy_move_probabilities((5, 5), (5, 8))
    w = {"east": math.exp(0.33 * 12), "south": math.exp(0.33 * 6), "north": math.exp(0.33 * 6), "west": 1.0}
    z = sum(w.values())
    assert p["stay"] == pytest.approx(0.2)
    for k in w:
        assert p[k] == pytest.approx(0.8 * w[k] / z)
    # corner (1, 1): north and west are obstacles; agent exactly south-east: both free moves at 45 degrees
    p = enemy_move_probabilities((1, 1), (5, 5))
    assert p["north"] == p["west"] == 0
    assert p["east"] == pytest.approx(0.4) and p["south"] == pytest.approx(0.4)
    # far away (dist 17 > 15): T = 1
    p = enemy_move_probabilities((6, 12), (23, 12))
    w = {"south": math.exp(0.33), "east": math.exp(0.165), "west": math.exp(0.165), "north": 1.0}
    z = sum(w.values())
    for k in w:
        assert p[k] == pytest.approx(0.8 * w[k] / z)
    # middle band (4 < dist <= 15): dist 10 -> T = 9 - 5 = 4
    p = enemy_move_probabilities((6, 12), (6, 22))
    w = {"east": math.exp(0.33 * 4), "south": math.exp(0.66), "north": math.exp(0.66), "west": 1.0}
    z = sum(w.values())
    for k in w:
        assert p[k] == pytest.approx(0.8 * w[k] / z)
    assert sum(enemy_move_probabilities((9, 12), (18, 3)).values()) == pytest.approx(1.0)


def test_enemy_moves_sampled_with_app_a1_probabilities():
    env = SurvivalEnv()
    env.reset(seed=123)
    # agent (5, 2) bumps into the obstacle north of it and stays; enemy 0 is 3 cells east; others far away
    state = make_state((5, 2), enemies=[(5, 5), (23, 20), (23, 21), (23, 22)], food=[(1, 20)], energy=100)
    moves = {(0, 0): "stay", (0, 1): "east", (1, 0): "south", (0, -1): "west", (-1, 0): "north"}
    counts = dict.fromkeys(moves.values(), 0)
    n = 6000
    for _ in range(n):
        env.set_state(state)
        env.step(0)
        r, c = env.get_state()["enemies"][0]
        counts[moves[(r - 5, c - 5)]] += 1
    want = enemy_move_probabilities((5, 5), (5, 2))
    for k, q in want.items():
        assert abs(counts[k] / n - q) < 5 * math.sqrt(q * (1 - q) / n) + 1e-9, (k, counts[k] / n, q)
