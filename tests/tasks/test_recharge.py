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


@pytest.mark.parametrize("env_id", ["connrl/Robot-CHG-Behaviours-v0", "connrl/Robot-CHG-Behaviours-NoXY-v0"])
def test_check_env(env_id):
    check_env(gym.make(env_id).unwrapped, skip_render_check=True)


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


def test_shipped_recharging_lessons_are_the_teachers_demonstrations():
    """robot-chg.json holds 10 docking demonstrations (rooms B, C, A in turn) of about 500 teaching steps in all
    (6.7), and the teacher makes them again exactly from its seed."""
    from connrl.tasks.recharge import chg_lessons, make_chg_lessons

    shipped = chg_lessons(10)
    assert [lesson.meta["room"] for lesson in shipped] == ["B", "C", "A"] * 3 + ["B"]
    assert all(lesson.terminated and lesson.rewards[-1] == 100.0 for lesson in shipped)
    assert 400 <= sum(len(lesson) for lesson in shipped) <= 600
    again = make_chg_lessons(3, seed=0)
    for a, b in zip(again, shipped[:3], strict=False):
        np.testing.assert_allclose(a.inputs, b.inputs, atol=1e-6)
        assert a.actions.tolist() == b.actions.tolist()
    with pytest.raises(ValueError, match="the file has 10"):
        chg_lessons(11)


def test_own_rewards_are_each_behaviours_ch5_reinforcement():
    from connrl.tasks.recharge_together import own_reward

    far = np.full(24, 60.0)
    assert own_reward("DK", 4, False, True, False, None) == 100.0
    assert own_reward("DK", 4, True, False, False, None) == -10.0
    assert own_reward("DP", 4, False, False, True, None) == 100.0
    assert own_reward("DP", 0, False, False, False, None) == 0.0
    assert own_reward("WFL", 5, False, False, False, far) == -3.0  # backing up
    assert own_reward("WFR", 4, True, False, False, far) == -10.0
    assert own_reward("WFL", 4, False, False, False, far) == 0.0  # no wall within 32 in on the left


def test_training_env_files_each_run_of_one_behaviour_as_its_lesson():
    """Exp. 5: the chosen behaviour acts and learns; switching behaviour closes its lesson, learn_behaviours replays."""
    from connrl.experiments.behaviours import pretrain_behaviours
    from connrl.tasks.recharge_together import TrainingBehaviourEnv

    agents, trials, spent = pretrain_behaviours(30, np.random.default_rng(0))
    assert all(k >= 1 for k in trials.values()) and all(s >= 30 for s in spent.values())
    before = {t: len(a.book.memory) for t, a in agents.items()}
    env = TrainingBehaviourEnv(agents, max_steps=12)
    env.reset(seed=1, options={"room": "B"})
    for b in [2] * 5 + [3] * 4 + [2] * 3:  # WFL 5 steps, WFR 4, WFL 3: three lessons, the last cut by the time limit
        *_, trunc, info = env.step(b)
        assert info["behaviour"] == ("WFL", "DP", "WFL", "WFR")[b]
    assert trunc
    env.learn_behaviours()
    wfl, wfr = agents["WFL"].book.memory.lessons, agents["WFR"].book.memory.lessons
    assert len(wfl) == before["WFL"] + 2 and len(wfr) == before["WFR"] + 1
    assert [len(wfl[-2]), len(wfr[-1]), len(wfl[-1])] == [5, 4, 3] and wfl[-1].truncated


def test_behaviours_trained_within_a_budget_stay_within_it():
    """recharge-own-library: each behaviour trains only while a whole trial (at most 30 steps) still fits its budget;
    8.5's budget is split in its own proportions."""
    from connrl.experiments.behaviours import THESIS_BEHAVIOUR_STEPS, budget_split, train_within_budget
    from connrl.tasks.behaviours import Behaviour

    assert budget_split(7000) == THESIS_BEHAVIOUR_STEPS and budget_split(140) == {"DK": 40, "DP": 40, "WFL": 30,
                                                                                   "WFR": 30}
    budget = {"DK": 75, "DP": 40, "WFL": 60, "WFR": 29}
    lib, trials, spent = train_within_budget(budget, np.random.default_rng(0))
    assert all(spent[t] <= budget[t] for t in budget) and trials["WFR"] == 0 and trials["WFL"] == 2
    assert spent["WFL"] == 60  # wall following never ends early: 30 steps a trial
    assert all(isinstance(b, Behaviour) and b.meta == {"trials": trials[t], "steps": spent[t]} for t, b in lib.items())
    assert trials["DK"] >= 2 and spent["DK"] > 30  # a second trial starts while 30 more steps fit
