"""The scripted robot teachers (3.7, 5.4): DP and DK reach the goal, wall following earns reward."""

import numpy as np
import pytest

from connrl.envs.robot import (
    RobotTaskEnv,
    teach,
)


@pytest.mark.parametrize("task", ["DP", "DK"])
def test_teachers_reach_the_goal(task):
    env = RobotTaskEnv(task)
    rng = np.random.default_rng(123)
    wins = 0
    for i in range(20):
        lesson = teach(env, env.sample_task(rng), seed=i)
        obs, a, r, nobs, term, trunc = lesson[0]
        assert obs.shape == nobs.shape == (52,) and 0 <= a < 6
        wins += lesson[-1][4]
    assert wins >= 16  # scripted, not optimal: measured ~97% over 100 random starts


def test_wall_following_teacher_earns_reward():
    env = RobotTaskEnv("WFL")
    lesson = teach(env, (32, 150, 90), seed=0)
    assert len(lesson) == 30 and lesson[-1][5] and sum(t[2] for t in lesson) > 150


@pytest.mark.parametrize("room", ["A", "B", "C"])
def test_recharging_teacher_docks_from_every_room(room):
    """The scripted recharging teacher (Exp. 1's lessons): docking is the world's own success test."""
    from connrl.envs.robot.recharge import RechargeEnv
    from connrl.envs.robot.teachers import teach_chg

    env = RechargeEnv(obs="flat")
    rng = np.random.default_rng(7)
    lessons = [teach_chg(env, env.sample_start(rng, room), seed=i) for i in range(5)]
    assert all(lesson[-1][4] and lesson[-1][2] == 100.0 for lesson in lessons)
    assert all(len(lesson) < {"A": 60, "B": 120, "C": 90}[room] for lesson in lessons)  # a route, not a wander


def test_recharging_teacher_starts_pressed_into_any_corner():
    """Starts the route grid does not reach nearby (a body touching two walls) still find their route."""
    from connrl.envs.robot.recharge import RechargeEnv
    from connrl.envs.robot.teachers import teach_chg

    env = RechargeEnv(obs="high")
    corners = [(x, y) for x0, y0, x1, y1 in env.layout.rooms.values() for x in (x0 + 12.5, x1 - 12.5)
               for y in (y0 + 12.5, y1 - 12.5) if env.layout.is_free(x, y, margin=0.1)]
    assert len(corners) >= 8
    docked = [teach_chg(env, (x, y, 45.0), seed=i)[-1][4] for i, (x, y) in enumerate(corners)]
    assert sum(docked) >= len(corners) - 1  # scripted, not perfect: at most one miss


def test_recharging_teacher_docks_with_fifth_size_steps():
    """Exp. 4's world (6.6.4: every primitive action a fifth): the teacher, Exp. 4's reference, still docks."""
    from connrl.envs.robot.recharge import RechargeEnv
    from connrl.envs.robot.teachers import teach_chg

    env = RechargeEnv(obs="high", step_scale=0.2, max_steps=1000, success_reward=500.0)
    rng = np.random.default_rng(11)
    for i, room in enumerate("ABC"):
        lesson = teach_chg(env, env.sample_start(rng, room), seed=i)
        assert lesson[-1][4] and lesson[-1][2] == 500.0 and len(lesson) > 50  # five times the steps of a route
