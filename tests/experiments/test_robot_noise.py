"""5.5's noise experiment (connrl.experiments.robot_noise): its noisy runs are Exp. 1's, its noise-free world has no
noise (its verdict rule is connrl.report.verdicts, tested in tests/report)."""

import json
from pathlib import Path

from connrl.experiments.robot import RobotParams
from connrl.experiments.robot_noise import EXPERIMENTS
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
    env = make_env(RobotParams(task="DK", noise=False))
    assert not env.sim.sensor_noise and not env.sim.control_noise
    assert make_env(RobotParams(task="DK")).sim.control_noise  # on by default, as in Ch. 5


def test_the_variants_cover_each_task_both_ways():
    labels = [v.label for v in EXPERIMENTS[0].variants]
    assert labels == ["DP, noisy", "DP, noise-free", "DK, noisy", "DK, noise-free", "WFL, noisy", "WFL, noise-free"]
