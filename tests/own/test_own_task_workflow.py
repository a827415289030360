"""A user's day with connrl on their own task (issue 29), through the command line: train with evaluation and
checkpoints, interrupt, resume from the checkpoint, plot the log, tune two settings, load the best agent."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

import connrl
from connrl import cli
from connrl.own import callbacks
from connrl.own.callbacks import read_progress


def test_train_interrupt_resume_plot_tune_and_load_the_best(tmp_path, monkeypatch, capsys):
    out = tmp_path / "cp"
    base = ["train", "CartPole-v1", "--save", str(out), "--quiet", "--eval-every", "500", "--eval-episodes", "2",
            "--checkpoint-every", "400", "--option", "hidden=6"]
    real = callbacks.ProgressLog.on_trial_end

    def interrupt_after_1000(self, agent, stats):  # Ctrl-C in the middle of training
        real(self, agent, stats)
        if agent.steps_done >= 1000:
            raise KeyboardInterrupt

    monkeypatch.setattr(callbacks.ProgressLog, "on_trial_end", interrupt_after_1000)
    assert cli.main([*base, "--steps", "2000"]) == 130
    monkeypatch.setattr(callbacks.ProgressLog, "on_trial_end", real)
    stopped = json.loads((out / "agent.json").read_text())["steps_done"]
    assert 1000 <= stopped < 2000

    # the same command without --resume refuses to overwrite; with it, training goes on to exactly 2000 steps
    with pytest.raises(SystemExit, match="holds a trained agent already"):
        cli.main([*base, "--steps", "2000"])
    with pytest.raises(SystemExit, match="only --steps may change"):
        cli.main([*base[:-1], "hidden=8", "--steps", "2000", "--resume"])
    assert cli.main([*base, "--steps", "2000", "--resume"]) == 0
    agent = connrl.load(out, gym.make("CartPole-v1"))
    assert agent.steps_done == 2000
    rows = read_progress(out / "progress.csv")
    assert [r["trial"] for r in rows] == list(range(1, len(rows) + 1))  # one row per trial, none lost or doubled
    assert rows[-1]["steps"] == 2000 and np.all(np.diff([r["steps"] for r in rows]) > 0)
    assert sum(r["length"] for r in rows) == 2000
    evals = [r for r in rows if r["eval_mean"] is not None]
    assert len(evals) == 4  # at the first trial end past 500, 1000, 1500 and 2000 steps

    (out / "curve.png").unlink()
    assert cli.main(["plot", str(out)]) == 0
    assert (out / "curve.png").stat().st_size > 1000

    # the kept best agent is the one that scored the best evaluation: evaluated again from disk, the same mean
    best = connrl.load(out / "best", gym.make("CartPole-v1"))
    again = np.mean(connrl.evaluate(best, gym.make("CartPole-v1"), 2, seed=callbacks.EvalCallback(
        gym.make("CartPole-v1")).eval_seed))
    assert again == pytest.approx(max(r["eval_mean"] for r in evals))

    tune = ["tune", "CartPole-v1", "--space", "lr=0.02,0.1", "--space", "hidden=4:8", "--steps", "300", "--seeds",
            "1000", "--eval-episodes", "1", "--out", str(tmp_path / "tune"), "--trials"]
    assert cli.main([*tune, "2"]) == 0
    trials = (tmp_path / "tune" / "trials.csv").read_text().splitlines()
    assert len(trials) == 3
    assert cli.main([*tune, "3"]) == 0  # one more trial: the first two are kept, not redone
    assert (tmp_path / "tune" / "trials.csv").read_text().splitlines()[:3] == trials
    capsys.readouterr()
    assert "n_timesteps: 50000" in (tmp_path / "tune" / "best.yml").read_text()  # the shipped budget, not 300
    assert cli.main([*tune, "3", "--train-steps", "400"]) == 0  # all trials done: best.yml rewritten
    assert cli.main(["train", "CartPole-v1", "--hyperparams", str(tmp_path / "tune" / "best.yml"), "--quiet",
                     "--save", str(tmp_path / "tuned")]) == 0
    settings = json.loads((tmp_path / "tuned" / "settings.json").read_text())
    assert settings["steps"] == 400 and set(settings["options"]) == {"lr", "hidden"}
    assert connrl.load(tmp_path / "tuned").steps_done == 400


def test_resume_keeps_the_runs_own_steps_and_damaged_files_are_one_line(tmp_path, capsys):
    out = tmp_path / "r"
    assert cli.main(["train", "CartPole-v1", "--steps", "300", "--quiet", "--save", str(out)]) == 0
    assert cli.main(["train", "CartPole-v1", "--quiet", "--save", str(out), "--resume"]) == 0
    assert "trained for 300 steps already" in capsys.readouterr().out  # not the default 50,000
    (out / "progress.csv").write_bytes(b"\xff\xfe broken")
    with pytest.raises(SystemExit, match="progress.csv: is not a connrl progress.csv"):
        cli.main(["train", "CartPole-v1", "--steps", "600", "--quiet", "--save", str(out), "--resume"])
    (tmp_path / "file").write_text("")
    with pytest.raises(SystemExit, match="cannot write TensorBoard logs in"):
        cli.main(["train", "CartPole-v1", "--steps", "300", "--quiet", "--save", str(tmp_path / "t"),
                  "--tensorboard", str(tmp_path / "file" / "x")])
    settings = json.loads((out / "settings.json").read_text())
    settings["env_kwargs"] = {"env_id": "evilmod:Evil"}
    (out / "settings.json").write_text(json.dumps(settings))
    with pytest.raises(SystemExit, match="look like 'module:name' imports"):
        cli.main(["evaluate", str(out)])


def test_train_keep_n_keeps_the_last_numbered_checkpoints_and_monitor_csv(tmp_path, capsys):
    out = tmp_path / "cp"
    assert cli.main(["train", "CartPole-v1", "--steps", "900", "--checkpoint-every", "300", "--keep", "2", "--quiet",
                     "--save", str(out), "--option", "hidden=4"]) == 0
    kept = sorted((out / "checkpoints").iterdir())
    steps = [connrl.load(p).steps_done for p in kept]
    assert len(kept) == 2 and steps[-1] == 900 == connrl.load(out).steps_done and 600 <= steps[0] < 900
    assert [p.name for p in kept] == [f"step-{s:011d}" for s in steps]
    rows = read_progress(out / "progress.csv")
    assert len((out / "monitor.csv").read_text().splitlines()) == len(rows) + 2
