"""The scripted survival teacher: complete lessons, and it heads for adjacent food."""

import numpy as np
import pytest

from connrl.envs.survival import (
    SurvivalEnv,
    scripted_teacher_action,
    scripted_teacher_lesson,
)
from tests.envs.survival_scenes import make_state


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
