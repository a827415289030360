"""Ch. 5 experiments: specs, the run function's protocol and determinism, lesson regeneration, CLI smoke run."""

from __future__ import annotations

import json

import numpy as np
import pytest

from connrl import cli
from connrl.core.lesson_files import load_lessons
from connrl.experiments import robot
from connrl.experiments.robot import EXPERIMENTS, ROBOT_PARAMS, first_reaching, make_taught_lessons, run_robot

TINY = {**ROBOT_PARAMS, "trials": 4, "test_every": 2, "test_tasks": 3, "lessons_per_trial": 3}


def test_specs_cover_chapter_5():
    names = {s.name for s in EXPERIMENTS}
    assert names == {"robot-teaching-dp", "robot-teaching-dk", "robot-teaching-wfl", "robot-lambda-dp",
                     "robot-lambda-wfl", "robot-repairs-3", "robot-repairs-10", "robot-single-layer",
                     "robot-dp-geometry", "robot-dk-geometry"}
    for s in EXPERIMENTS:
        params, runs = s.resolve("full")
        assert runs == 7 and params["trials"] == 300 and params["test_every"] == 10 and params["test_tasks"] == 50
    dp = next(s for s in EXPERIMENTS if s.name == "robot-teaching-dp")
    assert {v.label: v.thesis.get("trials_to_2.5") for v in dp.variants} == {
        "no teaching": 280, "3 lessons": 20, "10 lessons": 10}
    lam = next(s for s in EXPERIMENTS if s.name == "robot-lambda-dp")
    assert [v.thesis.get("trials_to_5") for v in lam.variants] == [280, 140, 65, None, None]
    single = next(s for s in EXPERIMENTS if s.name == "robot-single-layer")
    assert single.params["hidden_fraction"] == 0 and single.params["binary_low"] == 0.0
    assert [v.params["lr"] for v in single.variants] == [0.04, 0.04, 0.03]  # 5.4.4


def _variant_params(name: str, label: str) -> dict:
    spec = next(s for s in EXPERIMENTS if s.name == name)
    params, _ = spec.resolve("full")
    v = next(v for v in spec.variants if v.label == label)
    return {k: x for k, x in {**params, **v.params}.items() if k != "paths"}


def test_geometry_studies_vary_only_the_geometry():
    dp = next(s for s in EXPERIMENTS if s.name == "robot-dp-geometry")
    combos = {(v.params["door_width"], v.params["dp_heading"], v.params["lessons"]) for v in dp.variants}
    assert combos == {(w, h, n) for w in (36.0, 48.0) for h in (180.0, 45.0) for n in (0, 3, 10)}
    assert {v.thesis["trials_to_2.5"] for v in dp.variants if v.params["lessons"] == 10} == {10}
    # in the SPEC geometry the studies' variants are exactly the thesis experiments' variants
    for n, label in ((0, "no teaching"), (3, "3 lessons"), (10, "10 lessons")):
        assert _variant_params("robot-dp-geometry", f"36-in doors, any heading, {n} lessons") == \
            _variant_params("robot-teaching-dp", label)
    assert _variant_params("robot-dk-geometry", "30 deg, multi-layer, 10 lessons") == \
        _variant_params("robot-teaching-dk", "10 lessons")
    assert _variant_params("robot-dk-geometry", "30 deg, single-layer, 10 lessons") == \
        _variant_params("robot-single-layer", "DK single-layer")
    tight = _variant_params("robot-dk-geometry", "10 deg, single-layer, 10 lessons")
    assert tight == {**_variant_params("robot-single-layer", "DK single-layer"), "dock_tolerance": 10.0}


def test_other_geometry_gets_its_own_taught_lessons():
    wide = robot.taught_lessons("DP", 3, -0.5, door_width=48.0)
    again = robot.taught_lessons("DP", 3, -0.5, door_width=48.0)
    shipped = robot.taught_lessons("DP", 3)
    for a, b in zip(wide, again, strict=True):  # deterministic
        np.testing.assert_array_equal(a.inputs, b.inputs)
    # the teacher demonstrated in the 48-in layout: its first lesson is what the teacher does there
    env = robot.make_env(dict(ROBOT_PARAMS, door_width=48.0))
    assert env.layout.doors["A"].width == 48.0
    direct = make_taught_lessons("DP", n=1, seed=0, env=env)[0]
    np.testing.assert_array_equal(wide[0].inputs, direct.inputs)
    assert all(w.meta["success"] for w in wide)
    assert any(a.inputs.shape != b.inputs.shape or not np.array_equal(a.inputs, b.inputs)
               for a, b in zip(wide, shipped, strict=True))
    # docking tolerance matters for DK only
    assert all(np.array_equal(a.inputs, b.inputs) for a, b in
               zip(robot.taught_lessons("DP", 2, dock_tolerance=10.0), robot.taught_lessons("DP", 2), strict=True))
    with pytest.raises(ValueError, match="the teacher made 10"):
        robot.taught_lessons("DP", 11, door_width=48.0)
    r = run_robot(dict(TINY, door_width=48.0, dp_heading=45.0, lessons=3), np.random.default_rng(1))
    assert r.curve_x == [0, 2, 4]


def test_first_reaching():
    assert first_reaching([0, 10, 20, 30], [0.0, 2.4, 2.6, 1.0], 2.5) == 20
    assert first_reaching([0, 10], [0.0, 1.0], 2.5) is None


def test_run_protocol_and_determinism():
    a = run_robot(dict(TINY, lessons=3), np.random.default_rng(5))
    b = run_robot(dict(TINY, lessons=3), np.random.default_rng(5))
    assert a.curve_x == [0, 2, 4]  # a test before learning and after every test_every trials
    assert a.curve_y == b.curve_y and a.metrics == b.metrics
    assert all(-10.0 <= y <= 100.0 for y in a.curve_y)  # reinforcement per step is within the reward range
    assert set(a.metrics) == {"trials_to_2.5", "trials_to_5", "final_performance", "mean_performance"}


def test_wfl_single_layer_run():
    r = run_robot(dict(TINY, task="WFL", lessons=2, hidden_fraction=0.0, momentum=0.0, binary_low=0.0, lr=0.03,
                       paths=2), np.random.default_rng(0))
    assert len(r.extra["paths"]) == 2 and len(r.extra["paths"][0]["poses"]) == ROBOT_PARAMS["max_steps"] + 1


def test_lesson_files_are_regenerated_deterministically():
    shipped = load_lessons(robot.lesson_path("DK"), env_id="connrl/Robot-DK-v0")
    fresh = make_taught_lessons("DK", n=2, seed=0)
    for s, f in zip(shipped[:2], fresh, strict=True):
        np.testing.assert_allclose(s.inputs, f.inputs)
        np.testing.assert_array_equal(s.actions, f.actions)
    doc = json.loads(robot.lesson_path("WFL").read_text())
    assert "scripted teacher" in doc["source"] and len(doc["lessons"]) == 5


def test_cli_tiny_smoke_and_results_section(tmp_path):
    assert cli.main(["run", "robot-teaching-dp", "--profile", "tiny", "--out", str(tmp_path), "--workers", "1",
                     "--quiet"]) == 0
    summary = json.loads((tmp_path / "robot-teaching-dp" / "summary.json").read_text())
    assert summary["variants"]["10 lessons"]["quantities"]["trials_to_2.5"]["thesis"] == 10
    md = robot.results_section(tmp_path, tmp_path / "RESULTS.md")
    assert "robot-teaching-dp" in md and "| 10 lessons |" in md
    assert (tmp_path / "robot-teaching-dp" / "solution-paths.png").exists()


def test_geometry_sections_draw_panels_and_notes(tmp_path):
    for name in ("robot-dp-geometry", "robot-dk-geometry"):
        assert cli.main(["run", name, "--profile", "tiny", "--out", str(tmp_path), "--workers", "1", "--quiet"]) == 0
    md = robot.results_section(tmp_path, tmp_path / "docs" / "RESULTS.md")
    assert "**Door width and start heading**" in md and "**Docking tolerance**" in md
    assert "| 48-in doors, facing +-45, 10 lessons |" in md
    for name in ("robot-dp-geometry", "robot-dk-geometry"):
        assert (tmp_path / name / "panels.png").exists()
        assert (tmp_path / "docs" / "figures" / f"{name}-curves.png").exists()


def test_results_section_without_runs(tmp_path):
    assert "No Ch. 5 results yet" in robot.results_section(tmp_path, tmp_path / "RESULTS.md")


def test_bad_task_is_rejected():
    with pytest.raises(ValueError, match="task must be one of"):
        run_robot(dict(TINY, task="CHG"), np.random.default_rng(0))
