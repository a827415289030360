"""5.5's noise experiment (connrl.experiments.robot_noise): its noisy runs are Exp. 1's, its noise-free world has no
noise, and the "about the same" reading by hand."""

import json
from pathlib import Path

import numpy as np
import pytest

from connrl.experiments.robot_noise import EXPERIMENTS, RobotNoiseParams
from connrl.experiments.spec import about_the_same
from connrl.tasks.robot import make_env

GOLDEN = json.loads((Path(__file__).parents[1] / "data" / "tiny_e172482.json").read_text())


def test_the_noisy_variants_are_exp_1s_runs_and_the_noise_free_ones_differ():
    """Recorded before this experiment existed: robot-teaching-dp/dk/wfl's tiny runs with 10/10/5 lessons."""
    summary_noise = GOLDEN["robot-noise"]["per_run"]
    for task, exp, label in (("DP", "robot-teaching-dp", "10 lessons"), ("DK", "robot-teaching-dk", "10 lessons"),
                             ("WFL", "robot-teaching-wfl", "5 lessons")):
        exp1 = GOLDEN[exp]["per_run"][label]["final_performance"]
        assert summary_noise[f"{task}, noisy"]["final_performance"] == exp1
        assert summary_noise[f"{task}, noise-free"]["final_performance"] != exp1


def test_noise_off_means_exact_moves_and_readings():
    env = make_env(RobotNoiseParams(task="DK", noise=False))
    assert not env.sim.sensor_noise and not env.sim.control_noise
    assert make_env(RobotNoiseParams(task="DK")).sim.control_noise  # on by default, as in Ch. 5


def test_the_variants_cover_each_task_both_ways():
    labels = [v.label for v in EXPERIMENTS[0].variants]
    assert labels == ["DP, noisy", "DP, noise-free", "DK, noisy", "DK, noise-free", "WFL, noisy", "WFL, noise-free"]


def test_about_the_same_by_hand():
    # means 4 and 4.5: difference 0.5; variances 1 and 1 over 4 runs each: SE = sqrt(1/4 + 1/4) = 0.7071
    noisy, free = [3.0, 5.0, 3.0, 5.0], [3.5, 5.5, 3.5, 5.5]
    var = np.var(noisy, ddof=1)  # 4/3
    diff, two_se, same = about_the_same(noisy, free)
    assert diff == pytest.approx(0.5) and two_se == pytest.approx(2 * np.sqrt(2 * var / 4)) and same
    diff, two_se, same = about_the_same([4.0, 4.1, 3.9, 4.0], [5.0, 5.1, 4.9, 5.0])  # +1.0, 25 % and far past 2 SE
    assert diff == pytest.approx(1.0) and not same
    assert about_the_same([10.0], [10.5])[2]  # one run each: no SE, judged by the 10 % rule alone
    assert not about_the_same([10.0], [100.0])[2]
