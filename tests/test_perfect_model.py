"""scripts/own_task/planning_grouping.py's perfect model: what it predicts for every action is what the world then
does when that action is taken, up to and including the step that ends the episode, and simulating leaves the
world where it was."""

import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts" / "own_task"))
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_gymnasium import TEACHERS  # noqa: E402
from planning_grouping import PerfectModel  # noqa: E402


class _Raw:
    def encode(self, obs):
        return np.asarray(obs, float)


@pytest.mark.parametrize("task", ["CartPole-v1", "Acrobot-v1", "MountainCar-v0"])
def test_the_perfect_model_predicts_the_next_step_of_every_action(task):
    env, twin = gym.make(task), gym.make(task)  # the twin takes the same actions but is never simulated from
    obs, _ = env.reset(seed=3)
    twin.reset(seed=3)
    model, rng, teacher = PerfectModel(env, _Raw()), np.random.default_rng(0), TEACHERS[task][1]
    terminated = truncated = False
    share = 1.0 if task == "CartPole-v1" else 0.2  # random moves drop the pole; the teacher reaches the others' goals
    while not (terminated or truncated):
        outcomes = model.simulate(None, list(range(env.action_space.n)))
        a = int(rng.integers(env.action_space.n)) if rng.random() < share else teacher(obs)
        obs, r, terminated, truncated, _ = env.step(a)
        t_obs, t_r, t_term, _, _ = twin.step(a)
        np.testing.assert_allclose(obs, t_obs)  # simulating did not move the world
        np.testing.assert_allclose(outcomes[a][0], obs)
        assert (outcomes[a][1], outcomes[a][2]) == (float(r), bool(terminated)) == (float(t_r), bool(t_term))
    assert terminated  # the goal (or CartPole's fall) was predicted, not only the steps before it
