"""Survival task (thesis Ch. 4, SPEC.md section 2): sensors vs SPEC's drawings, rules, App. A.1, symmetry."""

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import connrl.envs  # noqa: F401  (registers connrl/Survival-v0)
from connrl.envs.survival import (
    ACTION_ROTATION,
    AGENT_START,
    ENEMY_STARTS,
    GRID_SIZE,
    KEYMAP,
    OBS_SLICES,
    OBSTACLES,
    SENSOR_OFFSETS,
    SENSOR_TYPES,
    SurvivalEnv,
    enemy_move_probabilities,
    environment_sets,
    rotate_observation,
    scripted_teacher_action,
    scripted_teacher_lesson,
)

# SPEC.md section 2, copied verbatim ("I" = the agent start, "E" = enemy starts).
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
# receptive fields as SPEC defines the letters: X plus (5 cells), O 3x3 (9), Y diamond (13), o one cell
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


@pytest.fixture(scope="module")
def env():
    e = SurvivalEnv()
    e.reset(seed=0)
    return e


# ------------------------------------------------------------------------------------- API and layout
@pytest.mark.parametrize("rep", ["global", "local"])
def test_check_env(rep):
    for mode in (None, "ansi", "rgb_array"):
        check_env(gym.make("connrl/Survival-v0", action_representation=rep, render_mode=mode).unwrapped)


def test_registered_and_unit_counts():
    env = gym.make("connrl/Survival-v0")
    obs, _ = env.reset(seed=1)
    assert env.observation_space.shape == (145,) and env.action_space.n == 4
    assert [s.stop - s.start for s in OBS_SLICES.values()] == [52, 32, 40, 16, 5]
    assert [len(SENSOR_OFFSETS[k]) for k in ("food", "enemy", "obstacle")] == [52, 32, 40]
    assert set(np.unique(obs)) <= {-0.5, 0.5}


def test_bad_arguments_are_rejected_with_clear_errors():
    with pytest.raises(ValueError, match="action_representation"):
        SurvivalEnv(action_representation="polar")
    with pytest.raises(ValueError, match="render_mode"):
        SurvivalEnv(render_mode="human")
    with pytest.raises(ValueError, match="max_steps"):
        SurvivalEnv(max_steps=0)
    env = SurvivalEnv()
    with pytest.raises(RuntimeError, match="reset"):
        env.step(0)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(4)
    with pytest.raises(ValueError, match="unknown reset options"):
        env.reset(options={"layout": 3})
    with pytest.raises(ValueError, match="obstacle"):
        env.reset(options={"food": [(0, 0)]})


def test_grid_is_spec_grid_and_8_fold_symmetric():
    rows = GRID_DRAWING.strip().splitlines()
    assert OBSTACLES.shape == (25, 25) and len(rows) == 25
    assert (OBSTACLES == np.array([[ch == "O" for ch in row] for row in rows])).all()
    assert rows[AGENT_START[0]][AGENT_START[1]] == "I"
    assert all(rows[r][c] == "E" for r, c in ENEMY_STARTS)
    for k in range(4):
        assert (np.rot90(OBSTACLES, k) == OBSTACLES).all()
        assert (np.rot90(OBSTACLES, k).T == OBSTACLES).all()


def test_start_state():
    env = SurvivalEnv()
    obs, info = env.reset(seed=5)
    st = env.get_state()
    assert info["position"] == AGENT_START == (18, 12) and info["energy"] == 40
    assert [tuple(e) for e in st["enemies"]] == list(ENEMY_STARTS)
    food = np.argwhere(st["food"])
    assert len(food) == 15 == info["food_left"]
    assert not OBSTACLES[food[:, 0], food[:, 1]].any()
    assert not {tuple(f) for f in food} & {AGENT_START, *ENEMY_STARTS}
    assert (obs[140:145] == -0.5).all()  # no previous action, no collision


# ------------------------------------------------------------------------------------------- sensors
@pytest.mark.parametrize("kind,drawing", [("food", FOOD_DRAWING), ("enemy", ENEMY_DRAWING),
                                          ("obstacle", OBSTACLE_DRAWING)])
def test_sensor_layout_matches_spec_drawing(kind, drawing):
    drawn, (top, bottom) = parse_drawing(drawing)
    ours = env_sensors(kind)
    assert {s for s in ours if top <= s[1] <= bottom} == drawn  # exactly the rows the drawing shows
    completed = set().union(*(rotate_set(drawn, k) for k in range(4)))  # SPEC: arrays are rotation invariant
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


def test_local_orientation_follows_moves():
    env = SurvivalEnv(action_representation="local")
    env.reset(seed=0)
    far = [(1, 12)] * 4
    env.set_state(make_state((18, 5), enemies=far, food=[(1, 1)], energy=100, orientation=1))  # facing east
    _, _, _, _, info = env.step(KEYMAP["w"])  # front = east
    assert info["position"] == (18, 6) and info["orientation"] == 1
    _, _, _, _, info = env.step(KEYMAP["a"])  # left of east = north
    assert info["position"] == (17, 6) and info["orientation"] == 0
    obs, _, _, _, info = env.step(KEYMAP["d"])  # right of north = east
    assert info["position"] == (17, 7) and info["orientation"] == 1
    assert obs[140:144].tolist() == [-0.5, 0.5, -0.5, -0.5]  # history holds the local action "right"
    # thesis 4.2.3: four consecutive "right" moves without collision return to the same cell and orientation
    env.set_state(make_state((18, 12), enemies=far, food=[(1, 1)], energy=100, orientation=2))
    for _ in range(4):
        _, _, _, _, info = env.step(KEYMAP["d"])
        assert not info["collided"]
    assert info["position"] == (18, 12) and info["orientation"] == 2
    # a collision still turns the agent to the attempted direction
    env.set_state(make_state((12, 13), enemies=far, food=[(1, 1)], energy=100, orientation=0))
    _, _, _, _, info = env.step(KEYMAP["a"])  # west of (12, 13) is the obstacle (12, 12)
    assert info["collided"] and info["position"] == (12, 13) and info["orientation"] == 3


def test_random_initial_orientation():
    env = SurvivalEnv(action_representation="local")
    assert {env.reset(seed=s)[1]["orientation"] for s in range(40)} == {0, 1, 2, 3}
    assert {SurvivalEnv().reset(seed=s)[1]["orientation"] for s in range(10)} == {0}


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


def test_energy_food_and_rewards(env):
    env.set_state(make_state((18, 12), enemies=[(1, 12)] * 4, food=[(17, 12), (1, 1)], energy=40))
    obs, r, term, trunc, info = env.step(KEYMAP["w"])  # north onto the food
    assert (r, term, trunc) == (0.4, False, False)
    assert info["energy"] == 40 - 1 + 15 and info["food_eaten"] == 1 and info["food_left"] == 1
    assert not env.get_state()["food"][17, 12]
    obs, r, term, trunc, info = env.step(KEYMAP["s"])
    assert (r, info["energy"], info["collided"]) == (0.0, 53, False)
    env.set_state(make_state((12, 13), enemies=[(1, 12)] * 4, food=[(1, 1)], energy=10))
    obs, r, term, trunc, info = env.step(KEYMAP["a"])  # bump into (12, 12): still costs energy
    assert info["collided"] and info["position"] == (12, 13) and info["energy"] == 9 and obs[144] == 0.5
    assert obs[140:144].tolist() == [-0.5, -0.5, -0.5, 0.5]


def test_play_ends(env):
    far = [(1, 12)] * 4
    env.set_state(make_state((18, 12), enemies=far, food=[(1, 1)], energy=1))  # starves
    _, r, term, trunc, info = env.step(0)
    assert (r, term, trunc, info["outcome"], info["energy"]) == (-1.0, True, False, "starved", 0)
    env.set_state(make_state((18, 12), enemies=far, food=[(17, 12)], energy=1))  # last food at energy 1
    _, r, term, trunc, info = env.step(0)
    assert (r, term, info["outcome"], info["energy"]) == (0.4, True, "all_food", 15)
    env.set_state(make_state((18, 12), enemies=[(17, 12)] * 4, food=[(1, 1)]))  # walks into an enemy
    _, r, term, trunc, info = env.step(0)
    assert (r, term, info["outcome"]) == (-1.0, True, "killed")
    with pytest.raises(RuntimeError):
        env.step(0)


def test_enemy_catching_the_agent_kills_it():
    env = SurvivalEnv()
    env.reset(seed=0)
    for _ in range(50):  # the enemy north of the agent's new cell steps onto it with probability ~0.8
        env.set_state(make_state((18, 12), enemies=[(17, 13), (1, 12), (1, 12), (1, 12)], food=[(1, 1)]))
        _, r, term, _, info = env.step(KEYMAP["d"])  # east to (18, 13)
        if term:
            break
    assert (r, term, info["outcome"]) == (-1.0, True, "killed")
    assert tuple(env.get_state()["enemies"][0]) == info["position"] == (18, 13)


def test_max_steps_truncates():
    env = SurvivalEnv(max_steps=3)
    env.reset(seed=0)
    env.set_state(make_state((12, 13), enemies=[(1, 12)] * 4, food=[(1, 1)], energy=40))
    for _ in range(3):
        _, _, term, trunc, info = env.step(3)  # keep bumping into (12, 12)
    assert (term, trunc, info["outcome"]) == (False, True, "timeout")


# ------------------------------------------------------------------------------------ reproducibility
def _trajectory(env, seed, options=None, n=60):
    obs, info = env.reset(seed=seed, options=options)
    out = [obs]
    rng = np.random.default_rng(99)
    for _ in range(n):
        obs, r, term, trunc, info = env.step(int(rng.integers(4)))
        out += [obs, np.array([r, term, trunc, info["energy"], *info["position"]], dtype=float)]
        if term or trunc:
            break
    return out, env.get_state()


@pytest.mark.parametrize("rep", ["global", "local"])
def test_same_seed_same_play(rep):
    a, sa = _trajectory(SurvivalEnv(action_representation=rep), 7)
    b, sb = _trajectory(SurvivalEnv(action_representation=rep), 7)
    c, _ = _trajectory(SurvivalEnv(action_representation=rep), 8)
    assert len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert np.array_equal(sa["enemies"], sb["enemies"])
    assert not (len(a) == len(c) and all(np.array_equal(x, y) for x, y in zip(a, c, strict=True)))


def test_layout_seed_fixes_food_not_dynamics():
    env = SurvivalEnv()
    env.reset(seed=1, options={"layout_seed": 42})
    food1 = env.get_state()["food"]
    env.reset(seed=2, options={"layout_seed": 42})
    assert np.array_equal(food1, env.get_state()["food"])
    env.reset(seed=1, options={"layout_seed": 43})
    assert not np.array_equal(food1, env.get_state()["food"])
    (_, s1), (_, s2) = (_trajectory(SurvivalEnv(), s, {"layout_seed": 42}) for s in (1, 2))
    assert not np.array_equal(s1["enemies"], s2["enemies"])  # enemy moves come from np_random
    env.reset(seed=0, options={"food": [(17, 12), (5, 5)]})
    assert env.get_state()["food"].sum() == 2
    train, test = environment_sets(0)
    assert len(train) == 300 and len(test) == 50 and len(set(train) | set(test)) == 350
    assert environment_sets(0) == (train, test) and environment_sets(1) != (train, test)


def test_get_set_state_is_a_deep_copy_and_replays_with_rng():
    env = SurvivalEnv()
    env.reset(seed=3)
    state = env.get_state(include_rng=True)
    future = [env.step(a)[0] for a in (0, 3, 3, 0)]
    state_copy = env.get_state()
    state_copy["enemies"][:] = 0  # mutating a copy does not touch the env
    assert env.get_state()["enemies"].max() > 0
    env.set_state(state)
    again = [env.step(a)[0] for a in (0, 3, 3, 0)]
    assert all(np.array_equal(x, y) for x, y in zip(future, again, strict=True))
    model = SurvivalEnv()  # the "perfect model" (4.2.5): step a copy of the true state, own randomness
    model.reset(seed=100)
    model.set_state(env.get_state())
    assert np.array_equal(model.observe(), env.observe())


# --------------------------------------------------------------------------------------- render/teach
def test_renders():
    env = SurvivalEnv(render_mode="ansi")
    env.reset(seed=0)
    text = env.render()
    lines = text.splitlines()
    assert lines[1 + 18][3 + 12] == "I" and lines[1 + 1][3 + 12] == "E" and text.count("$") == 15 + 1
    assert "energy  40" in text
    env = SurvivalEnv(render_mode="rgb_array", action_representation="local")
    env.reset(seed=0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    colours = {tuple(c) for c in frame.reshape(-1, 3)[::7]}
    obstacle, enemy, food, agent = (70, 74, 86), (200, 30, 40), (226, 160, 20), (30, 90, 220)
    assert {obstacle, enemy, food, agent} <= colours


def test_keymap():
    assert KEYMAP == {"w": 0, "d": 1, "s": 2, "a": 3}
    env = SurvivalEnv()
    env.reset(seed=0)
    env.set_state(make_state((18, 12), food=[(1, 1)]))
    assert env.step(KEYMAP["a"])[4]["position"] == (18, 11)


@pytest.mark.parametrize("rep", ["global", "local"])
def test_scripted_teacher(rep):
    env = SurvivalEnv(action_representation=rep)
    lesson, info = scripted_teacher_lesson(env, seed=0, options={"layout_seed": 2})
    assert info["food_eaten"] >= 10
    obs, a, r, next_obs, term, trunc = lesson[0]
    assert obs.shape == next_obs.shape == (145,) and a in range(4)
    assert np.array_equal(lesson[1][0], next_obs) and lesson[-1][4] or lesson[-1][5]
    rewards = [x[2] for x in lesson]
    assert set(rewards[:-1]) <= {0.0, 0.4} and rewards[-1] in (0.4, -1.0)
    assert (rewards[-1] == -1.0) == (info["outcome"] in ("killed", "starved"))
    assert rewards.count(0.4) in (info["food_eaten"], info["food_eaten"] - 1)
    # the teacher heads for adjacent food
    env.reset(seed=0)
    env.set_state(make_state((18, 12), food=[(18, 13)], orientation=0))
    assert env.step(scripted_teacher_action(env))[4]["position"] == (18, 13)
