"""CLI: help texts, clear errors before any work, and a tiny-profile smoke run of every experiment."""

import json
from pathlib import Path

import pytest

from connrl import cli
from connrl.experiments.registry import all_experiments


@pytest.mark.parametrize("sub", ["list", "run", "plot", "show", "teach", "results", "sweep", "make-lessons"])
def test_every_command_has_help(sub, capsys):
    with pytest.raises(SystemExit) as e:
        cli.main([sub, "--help"])
    assert e.value.code == 0
    assert "usage: connrl" in capsys.readouterr().out


def test_list_names_every_experiment(capsys):
    cli.main(["list"])
    out = capsys.readouterr().out
    for name in all_experiments():
        assert name in out


def test_unknown_experiment_lists_the_allowed_ones():
    with pytest.raises(SystemExit) as e:
        cli.main(["run", "pole-fulll"])
    assert "unknown experiment 'pole-fulll'" in str(e.value) and "pole-full" in str(e.value)


@pytest.mark.parametrize("args, word", [(["--profile", "huge"], "invalid choice"), (["--runs", "0"], ">= 1"),
                                        (["--runs", "two"], "whole number"), (["--seed", "-3"], ">= 0")])
def test_invalid_parameters_are_refused_before_work(args, word, capsys, tmp_path):
    with pytest.raises(SystemExit) as e:
        cli.main(["run", "pole-full", "--out", str(tmp_path), *args])
    assert e.value.code == 2 and word in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_unknown_teach_target():
    with pytest.raises(SystemExit, match="unknown teach target 'chess'; available: survival"):
        cli.main(["teach", "chess"])


def test_plot_before_run_is_a_clear_error(tmp_path):
    with pytest.raises(SystemExit, match="run `connrl run pole-full` first"):
        cli.main(["plot", "pole-full", "--out", str(tmp_path)])


GOLDEN = json.loads((Path(__file__).parent / "data" / "tiny_e172482.json").read_text())


def _same(a, b) -> bool:
    """Equal, numbers to 1e-9 relative: a least-squares fit (the complexity exponents) moves in its last bits with
    the machine (the CPU the compiled and BLAS code is chosen for); another seed or a changed algorithm moves far
    more."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float):
        return a == pytest.approx(b, rel=1e-9, abs=1e-12, nan_ok=True)
    return a == b


def test_same_tells_bit_noise_from_a_change():
    assert _same({"x": [1.8862563548438562, 2]}, {"x": [1.8862563548438558, 2]})
    assert not _same({"x": [1.8862, 2]}, {"x": [1.8863, 2]}) and not _same({"x": [1.0]}, {"y": [1.0]})


@pytest.mark.parametrize("name", sorted(all_experiments()))
def test_every_experiment_runs_on_the_tiny_profile(name, tmp_path, capsys):
    """A smoke run through the CLI; its numbers equal those commit e172482 produced (at seed 0)."""
    assert cli.main(["run", name, "--profile", "tiny", "--seed", "0", "--out", str(tmp_path), "--workers", "1",
                     "--quiet"]) == 0
    summary = json.loads((tmp_path / name / "summary.json").read_text())
    assert summary["profile"] == "tiny" and summary["variants"]
    per_run = {v: {q: x["per_run"] for q, x in d["quantities"].items()} for v, d in summary["variants"].items()}
    assert _same(per_run, GOLDEN[name]["per_run"]), (per_run, GOLDEN[name]["per_run"])
    if name == "robot-dp-geometry":  # the reconstruction before the calibration, kept as a named variant
        old = GOLDEN["robot-teaching-dp@e172482"]["per_run"]
        assert _same({v: per_run[f"SPEC: 36-in doors, 24-in edges, {v.split()[0].replace('no', '0')} lessons"]
                      for v in old}, old)
    assert [p.name[:5] for p in (tmp_path / name / "runs").iterdir()] == ["tiny-"]  # one folder, of the profile
    assert (tmp_path / name / "curve.png").exists()
    assert cli.main(["plot", name, "--out", str(tmp_path)]) == 0
    assert cli.main(["show", name, "--out", str(tmp_path)]) == 0


def test_fresh_seed_experiments_are_their_experiments_at_seed_0():
    for name in ("survival-study1", "survival-study2", "cup-task1", "cup-task2", "cup-task3", "cup-task2-frozen"):
        assert GOLDEN[f"{name}-fresh"] == GOLDEN[name]  # not made apart: a fresh check must be its experiment
    for fresh, name in (("integration-fresh", "integration"), ("robot-teaching-dk-fresh", "robot-teaching-dk"),
                        ("recharge-behaviours-fresh", "recharge-behaviours")):  # issue 42's: some variants of theirs
        assert all_experiments()[fresh].resolve("tiny")[0] == all_experiments()[name].resolve("tiny")[0]
        assert all(GOLDEN[name]["per_run"][v] == vals for v, vals in GOLDEN[fresh]["per_run"].items())


def test_run_without_seed_starts_at_the_experiments_own(tmp_path):
    """A fresh-seed check run without --seed uses the seeds its title names, not development seed 0."""
    assert cli.main(["run", "survival-study2-fresh", "--profile", "tiny", "--out", str(tmp_path), "--workers", "1",
                     "--quiet"]) == 0
    summary = json.loads((tmp_path / "survival-study2-fresh" / "summary.json").read_text())
    assert summary["base_seed"] == 2000 and "seeds 2000-2006" in all_experiments()["survival-study2-fresh"].title
    assert cli.main(["run", "td-depth", "--profile", "tiny", "--out", str(tmp_path), "--workers", "1", "--quiet"]) == 0
    assert json.loads((tmp_path / "td-depth" / "summary.json").read_text())["base_seed"] == 0


@pytest.mark.parametrize("args, message", [
    (["--set", "lr=0.1", "--set", "learning_rate=0.1", "--seeds", "100:101"],
     "unknown parameter(s) 'learning_rate'; allowed: task, lessons"),
    (["--set", "lr", "--seeds", "100:101"], "--set expects key=value, got 'lr'"),
    (["--seeds", "7"], "--seeds expects A:B"),
    (["--seeds", "5:5"], "0 <= A < B"),
    (["--variant", "11 lessons", "--seeds", "0:1"], "has no variant '11 lessons'; variants: 'no teaching'"),
])
def test_sweep_refuses_bad_input_before_any_run(args, message, tmp_path):
    with pytest.raises(SystemExit) as e:
        cli.main(["sweep", "robot-teaching-dp", "--out", str(tmp_path), "--quiet", *args])
    assert message in str(e.value) and str(e.value).count("\n") == 0
    assert not any(tmp_path.iterdir())


def test_sweep_runs_one_run_per_seed_like_the_run_function(tmp_path, capsys):
    """Seeds A..B-1, each run seeded default_rng(seed) from the experiment's parameters plus the overrides."""
    import dataclasses

    import numpy as np

    from connrl.experiments.pole import PoleParams, run_pole

    assert cli.main(["sweep", "pole-full", "--set", "max_trials=3", "--set", "test_steps=200", "--set", "lr=1",
                     "--seeds", "5:7", "--out", str(tmp_path), "--workers", "1", "--quiet"]) == 0
    summary = json.loads(next(tmp_path.glob("sweep-pole-full-*/summary.json")).read_text())
    (variant,) = summary["variants"].values()
    assert variant["seeds"] == [5, 6]
    p = dataclasses.replace(PoleParams(), max_trials=3, test_steps=200, lr=1.0)
    direct = [run_pole(p, np.random.default_rng(s)).curve_y for s in (5, 6)]
    records = sorted((json.loads(f.read_text()) for f in tmp_path.rglob("seed-*.json")), key=lambda r: r["seed"])
    assert [r["curve_y"] for r in records] == direct and records[0]["params"]["lr"] == 1.0
    assert "mean curve" in capsys.readouterr().out


@pytest.mark.parametrize("world, files", [("robot", ["robot-dk.json", "robot-dp.json", "robot-wfl.json"]),
                                          ("survival", ["survival-global.json", "survival-local.json"])])
def test_make_lessons_rewrites_the_shipped_files_exactly(world, files, tmp_path, monkeypatch, capsys):
    from connrl.tasks import robot, survival

    shipped = robot.LESSON_DIR
    monkeypatch.setattr(robot, "LESSON_DIR", tmp_path)
    monkeypatch.setattr(survival, "LESSON_DIR", tmp_path)
    assert cli.main(["make-lessons", world]) == 0
    for name in files:
        assert (tmp_path / name).read_bytes() == (shipped / name).read_bytes(), name


def test_train_behaviours_writes_a_library(tmp_path, capsys):
    assert cli.main(["train-behaviours", "--out", str(tmp_path), "--trials", "2", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "DP: 2 trials" in out and (tmp_path / "library.json").exists()
    assert sorted(p.name for p in tmp_path.glob("*.npz")) == ["dk.npz", "dp.npz", "wfl.npz", "wfr.npz"]


def test_reproduce_runs_a_chapter_then_the_results_page(tmp_path, capsys):
    from connrl.experiments.registry import by_chapter, chapters, spec_modules
    assert chapters() == [4, 5, 6, 7, 8] and len(spec_modules()) == 13  # found, not listed: each with its CHAPTER
    assert sorted(s.name for s in by_chapter([4, 5, 6, 7, 8])) == sorted(all_experiments())
    assert {s.name: s.seed for s in by_chapter([5]) if s.seed} == {"robot-dp-calibration": 100, "robot-dp-fresh": 6000,
                                                                        "robot-teaching-dk-fresh": 4000}
    assert {s.name: s.full_runs for s in by_chapter([4, 5, 6, 7, 8]) if s.full_runs} == {"pole-hidden": 18}
    assert cli.main(["reproduce", "--chapters", "8", "--profile", "tiny", "--out", str(tmp_path), "--workers", "1",
                     "--quiet"]) == 0
    for name in ("integration", "steps-to-learn"):
        assert (tmp_path / name / "summary.json").exists()
    assert "## Chapter 8" in (tmp_path / "RESULTS.md").read_text()
    with pytest.raises(SystemExit, match="--chapters takes a comma-separated list of 4, 5, 6, 7, 8, got '3'"):
        cli.main(["reproduce", "--chapters", "3"])
    capsys.readouterr()
    assert cli.main(["reproduce", "--only", "pole-full", "--profile", "tiny", "--out", str(tmp_path), "--workers",
                     "1", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "[1/1] pole-full (alone: connrl run pole-full --profile tiny --seed 0)" in out and "1 experiments" in out
    assert "## Chapter 8" in (tmp_path / "RESULTS.md").read_text()  # the page keeps what was stored before
    with pytest.raises(SystemExit, match="--only takes .* got 'pole-ful': unknown pole-ful"):
        cli.main(["reproduce", "--only", "pole-ful"])
    with pytest.raises(SystemExit, match="unknown integration"):
        cli.main(["reproduce", "--chapters", "5", "--only", "integration"])


def test_params_prints_the_declarations_and_docs_parameters_is_current(capsys):
    """``connrl params NAME`` shows a value, its range, its note and what sets it otherwise; docs/PARAMETERS.md is
    ``connrl params``'s output (regenerate it with that command after declaring a parameter)."""
    assert cli.main(["params", "robot-teaching-dp"]) == 0
    rows = {line.split(" | ")[0][2:]: line.split(" | ")[1:] for line in capsys.readouterr().out.splitlines()
            if line.startswith("| ")}
    assert rows["lam"] == ["0.7", "float in [0, 1]", "", "(5.4.1) |"]
    assert rows["lessons"][2] == "no teaching: 0; 3 lessons: 3; 10 lessons: 10"
    assert cli.main(["params"]) == 0
    doc = (Path(__file__).parents[1] / "docs" / "PARAMETERS.md").read_text()
    assert capsys.readouterr().out == doc, "docs/PARAMETERS.md is stale: run `connrl params > docs/PARAMETERS.md`"
    with pytest.raises(SystemExit, match="unknown experiment 'nope'"):
        cli.main(["params", "nope"])
