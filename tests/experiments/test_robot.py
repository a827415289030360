"""Ch. 5 experiments: specs, the run function's protocol and determinism."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from connrl.experiments.robot import BEFORE_44, EXPERIMENTS, RobotParams, first_reaching, run_robot
from connrl.experiments.spec import as_dict

TINY = RobotParams(trials=4, test_every=2, test_tasks=3, lessons_per_trial=3)


def test_specs_cover_chapter_5():
    names = {s.name for s in EXPERIMENTS}
    assert names == {"robot-teaching-dp", "robot-teaching-dk", "robot-teaching-wfl", "robot-lambda-dp",
                     "robot-lambda-wfl", "robot-repairs-3", "robot-repairs-10", "robot-single-layer",
                     "robot-dp-geometry", "robot-dk-geometry", "robot-dp-calibration", "robot-dp-replay-order",
                     "robot-dp-fresh", "robot-dp-lesson-use", "robot-teaching-dk-fresh"}
    for s in EXPERIMENTS:
        params, runs = s.resolve("full")
        assert runs == 7 and params.trials == 300 and params.test_every == 10 and params.test_tasks == 50
    dp = next(s for s in EXPERIMENTS if s.name == "robot-teaching-dp")
    assert {v.label: v.thesis.get("trials_to_2.5") for v in dp.variants} == {
        "no teaching": 280, "3 lessons": 20, "10 lessons": 10}
    lam = next(s for s in EXPERIMENTS if s.name == "robot-lambda-dp")
    assert [v.thesis.get("trials_to_5") for v in lam.variants] == [280, 140, 65, None, None]
    single = next(s for s in EXPERIMENTS if s.name == "robot-single-layer")
    assert single.params.hidden_fraction == 0 and single.params.binary_low == 0.0
    assert [v.params["lr"] for v in single.variants] == [0.04, 0.04, 0.03]  # 5.4.4


def _variant_params(name: str, label: str) -> dict:
    spec = next(s for s in EXPERIMENTS if s.name == name)
    params, _ = spec.resolve("full")
    v = next(v for v in spec.variants if v.label == label)
    return {k: x for k, x in as_dict(spec.variant_params(params, v)).items() if k != "paths"}


def test_geometry_studies_vary_only_the_geometry():
    dp = next(s for s in EXPERIMENTS if s.name == "robot-dp-geometry")
    combos = {(v.params.get("door_width", 48.0), v.params.get("edge_jump", 44.0), v.params["lessons"])
              for v in dp.variants}
    assert combos == {(36.0, 24.0, 0), (36.0, 24.0, 3), (36.0, 24.0, 10), (36.0, 44.0, 0), (36.0, 44.0, 10),
                      (48.0, 24.0, 0), (48.0, 24.0, 10)}
    assert {v.thesis["trials_to_2.5"] for v in dp.variants if v.params["lessons"] == 10} == {10}
    # each variant is the thesis experiment's variant with only the geometry changed
    for n, label in ((0, "no teaching"), (3, "3 lessons"), (10, "10 lessons")):
        assert _variant_params("robot-dp-geometry", f"SPEC: 36-in doors, 24-in edges, {n} lessons") == \
            {**_variant_params("robot-teaching-dp", label), **BEFORE_44, "door_width": 36.0, "edge_jump": 24.0}
    assert _variant_params("robot-dp-fresh", "10 lessons, lambda=0.3") == \
        _variant_params("robot-lambda-dp", "lambda=0.3")
    assert _variant_params("robot-dp-calibration", "48-in doors, no teaching") == \
        {**_variant_params("robot-teaching-dp", "no teaching"), **BEFORE_44}
    assert _variant_params("robot-dk-geometry", "30 deg, multi-layer, 10 lessons") == \
        _variant_params("robot-teaching-dk", "10 lessons")
    assert _variant_params("robot-dk-geometry", "30 deg, single-layer, 10 lessons") == \
        _variant_params("robot-single-layer", "DK single-layer")
    tight = _variant_params("robot-dk-geometry", "10 deg, single-layer, 10 lessons")
    assert tight == {**_variant_params("robot-single-layer", "DK single-layer"), "dock_tolerance": 10.0}


def test_first_reaching():
    assert first_reaching([0, 10, 20, 30], [0.0, 2.4, 2.6, 1.0], 2.5) == 20
    assert first_reaching([0, 10], [0.0, 1.0], 2.5) is None


def test_run_protocol_and_determinism():
    a = run_robot(replace(TINY, lessons=3), np.random.default_rng(5))
    b = run_robot(replace(TINY, lessons=3), np.random.default_rng(5))
    assert a.curve_x == [0, 2, 4]  # a test before learning and after every test_every trials
    assert a.curve_y == b.curve_y and a.metrics == b.metrics
    assert all(-10.0 <= y <= 100.0 for y in a.curve_y)  # reinforcement per step is within the reward range
    assert set(a.metrics) == {"trials_to_2.5", "trials_to_5", "final_performance", "mean_performance"}


def test_wfl_single_layer_run():
    r = run_robot(replace(TINY, task="WFL", lessons=2, hidden_fraction=0.0, momentum=0.0, binary_low=0.0, lr=0.03,
                          paths=2), np.random.default_rng(0))
    assert len(r.extra["paths"]) == 2 and len(r.extra["paths"][0]["poses"]) == RobotParams().max_steps + 1


def test_bad_task_is_rejected():
    with pytest.raises(ValueError, match="task must be one of"):
        run_robot(replace(TINY, task="CHG"), np.random.default_rng(0))


def test_defaults_are_the_shipped_world():
    """RobotParams, the taught-lesson files' world and the environment agree on the calibrated geometry."""
    from connrl.envs.robot import DOOR_EDGE_JUMP, Layout, RobotTaskEnv
    from connrl.tasks.robot import SHIPPED_WORLD

    p = RobotParams()
    assert p.door_width == SHIPPED_WORLD["door_width"] == Layout.load("default").doors["B"].width == 49.0
    assert p.edge_jump == SHIPPED_WORLD["edge_jump"] == DOOR_EDGE_JUMP == RobotTaskEnv("DP").sim.edge_jump == 37.0
    sim = RobotTaskEnv("DP").sim  # issue 44's pick (docs/RECONSTRUCTION.md, "The robot world as a family")
    assert (p.sonar_origin, p.collision, p.edge_mark) == ("centre", "partial", "nearer")
    assert (sim.sonar_radius, sim.partial_moves, sim.edge_both) == (0.0, True, False)
    assert (p.dp_far, p.dp_lateral, p.pass_depth) == (52.0, 0.9, 0.0) == (RobotTaskEnv("DP")._dp_depth[1], 0.9, 0.0)


def test_copy_run_stops_at_full_agreement_and_the_teacher_passes():
    from connrl.experiments.robot_bounds import CopyParams, run_copy

    tiny = CopyParams(test_tasks=4, lessons=1, copy_epochs=300)
    r = run_copy(tiny, np.random.default_rng(0))
    assert r.metrics["agreement"] == 1.0 and r.metrics["epochs_to_copy"] < 300
    assert r.curve_x[-1] == 300 and len(r.curve_x) == len(r.curve_y)  # a finished copy's value carried forward
    assert r.curve_y[-1] == r.curve_y[r.curve_x.index(r.metrics["epochs_to_copy"])]
    t = run_copy(CopyParams(test_tasks=4, lessons=0, policy="teacher"), np.random.default_rng(0))
    assert t.metrics["passes"] == 4 and t.metrics["performance"] > 5  # the teacher reads the true pose
