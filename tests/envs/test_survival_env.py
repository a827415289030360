"""Survival env (thesis Ch. 4): Gymnasium API, start state, moves and orientation, rewards, play ends,
reproducibility, state copies, keys."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import connrl.envs  # noqa: F401  (registers connrl/Survival-v0)
from connrl.envs.survival import (
    AGENT_START,
    ENEMY_STARTS,
    KEYMAP,
    OBS_SLICES,
    OBSTACLES,
    SENSOR_OFFSETS,
    SurvivalEnv,
    environment_sets,
)
from tests.envs.survival_scenes import make_state


@pytest.fixture(scope="module")
def env():
    e = SurvivalEnv()
    e.reset(seed=0)
    return e


# ------------------------------------------------------------------------------------ API and start state
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


def test_keymap():
    assert KEYMAP == {"w": 0, "d": 1, "s": 2, "a": 3}
    env = SurvivalEnv()
    env.reset(seed=0)
    env.set_state(make_state((18, 12), food=[(1, 1)]))
    assert env.step(KEYMAP["a"])[4]["position"] == (18, 11)
