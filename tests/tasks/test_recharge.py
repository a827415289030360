"""CHG over behaviours (6.5): Gymnasium API, one primitive step of the chosen behaviour per step, applicability in
info, refusals, and the shipped DK behaviour docking from subgoal 2."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import connrl.envs  # noqa: F401
from connrl.envs.robot.recharge import RechargeEnv
from connrl.tasks.behaviours import load_library
from connrl.tasks.recharge import BehaviourEnv


def test_check_env():
    check_env(gym.make("connrl/Robot-CHG-Behaviours-v0").unwrapped, skip_render_check=True)


@pytest.mark.parametrize("b, task", [(0, "DK"), (1, "DP"), (2, "WFL"), (3, "WFR")])
def test_each_step_is_one_greedy_primitive_of_the_chosen_behaviour(b, task):
    lib = load_library()
    env, world = BehaviourEnv(lib), RechargeEnv()
    obs, info = env.reset(seed=5, options={"room": "A"})
    w_obs, w_info = world.reset(seed=5, options={"room": "A"})
    for _ in range(5):
        primitive = lib[task].act(w_info["task_obs"][task])  # the behaviour's own choice, computed independently
        obs, r, term, trunc, info = env.step(b)
        w_obs, w_r, w_term, w_trunc, w_info = world.step(primitive)
        assert info["primitive"] == primitive and info["behaviour"] == task
        np.testing.assert_array_equal(obs, w_obs)
        assert (r, term, trunc) == (w_r, w_term, w_trunc)
        assert info["applicable"].tolist() == [lib[t].applicable(w_info["task_obs"][t])
                                               for t in ("DK", "DP", "WFL", "WFR")]
        if term or trunc:
            break


def test_wall_following_is_always_applicable_and_bad_input_is_refused():
    env = BehaviourEnv()
    _, info = env.reset(seed=2)
    assert info["applicable"][2] and info["applicable"][3]
    with pytest.raises(ValueError, match="behaviour 0..3"):
        env.step(4)
    lib = load_library()
    del lib["WFR"]
    with pytest.raises(ValueError, match="lacks WFR"):
        BehaviourEnv(lib)
    with pytest.raises(ValueError, match="obs='high'"):
        BehaviourEnv(obs="flat")


def test_shipped_docking_behaviour_docks_from_subgoal_2():
    env = BehaviourEnv()
    docked = 0
    for seed in range(5):
        env.reset(seed=seed, options={"start": (36.0, 96.0, 270.0)})  # subgoal 2, facing south
        for _ in range(40):
            _, r, term, trunc, info = env.step(0)
            if term or trunc:
                break
        docked += r == 100.0 and info["success"]
    assert docked >= 4


def test_behaviour_goal_marks_the_step_that_passes_the_door():
    env = BehaviourEnv()
    _, info = env.reset(seed=0, options={"start": (114.0, 270.0, 90.0)})  # subgoal 3, facing the A-door
    rooms, goals = [info["room"]], []
    for _ in range(20):
        _, _, _, _, info = env.step(1)  # DP
        rooms.append(info["room"])
        goals.append(info["behaviour_goal"])
        if info["behaviour_goal"]:
            break
    assert goals[-1] and not any(goals[:-1]) and rooms[-1] == "C" and set(rooms[:-1]) == {"A"}
    _, _, _, _, info = env.step(2)  # WFL has no goal of its own
    assert info["behaviour_goal"] is False
