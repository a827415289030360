"""Run times: the expected times that order a pool and give its ETA, and where a pool's cores sat idle."""

from __future__ import annotations

import json
from types import SimpleNamespace

import pytest

from connrl.experiments import runner, timing
from connrl.experiments.executors import Progress
from connrl.experiments.registry import get_experiment
from connrl.experiments.runner import Batch, run_experiment, run_experiments
from connrl.experiments.store import check_record

TABLE = {"profile": "full", "seconds": {"a": {"x": 10.0, "y": 30.0, "z": 50.0}, "b": {"x": 2.0}}}


def _job(experiment, variant, profile="full", seed=0):
    return SimpleNamespace(experiment=experiment, variant=variant, seed=seed,
                           path=f"/o/{experiment}/runs/{profile}-abc/{variant}/seed-{seed}")


def test_expected_seconds_come_from_the_table_with_medians_for_what_it_lacks():
    jobs = [_job("a", "y"), _job("a", "new"), _job("c", "x")]
    got, calibrated = timing.expected_seconds(jobs, TABLE)
    assert [got[j.path] for j in jobs] == [30.0, 30.0, 20.0]  # a's median 30; all four's median (2, 10, 30, 50) 20
    assert calibrated
    assert timing.expected_seconds([_job("a", "x", "quick")], TABLE) == ({_job("a", "x", "quick").path: 10.0}, False)
    assert timing.expected_seconds([_job("a", "x")], {"profile": None, "seconds": {}})[0] == {_job("a", "x").path: 1.0}


def test_a_damaged_or_missing_table_only_costs_the_order(tmp_path):
    (tmp_path / "t.json").write_text("{not json")
    assert timing.load_run_times(tmp_path / "t.json") == {"profile": None, "seconds": {}}
    assert timing.load_run_times(tmp_path / "none.json") == {"profile": None, "seconds": {}}


def test_pool_usage_by_hand():
    # 2 cores, 12 s: runs [0, 10], [0, 4], [4, 8]; both cores busy until 8, then one run left until 10, nothing after
    recs = [{"started_at": a, "wall_time_s": b - a} for a, b in [(0, 10), (0, 4), (4, 8)]]
    use = timing.pool_usage(recs, 2, start=0.0, end=12.0)
    assert use["busy_s"] == 18 and use["idle_s"] == 6 and use["head_s"] == 0
    assert use["tail_s"] == 4 and use["tail_idle_s"] == 6  # 8..12 on 2 cores = 8 core-s, 2 of them busy
    assert use["utilisation"] == pytest.approx(0.75)


def test_per_experiment_sums_runs_and_counts_compiling_in_the_span():
    recs = [{"experiment": "a", "started_at": 100.0, "wall_time_s": 3.0, "cpu_time_s": 2.5, "compile_time_s": 1.0},
            {"experiment": "a", "started_at": 101.0, "wall_time_s": 1.0}]
    e = timing.per_experiment(recs)["a"]
    assert (e["runs"], e["run_s"], e["cpu_s"], e["compile_s"], e["longest_s"]) == (2, 4.0, 3.5, 1.0, 3.0)
    assert (e["first"], e["last"]) == (100.0, 104.0)


def test_progress_eta_is_what_is_left_over_the_workers_at_the_measured_speed():
    jobs = [_job("a", "x"), _job("a", "y")]
    p = Progress(jobs, "t", {jobs[0].path: 10.0, jobs[1].path: 30.0}, workers=2)
    assert p.eta_seconds() == 30.0  # 40 s over 2 workers is 20 s, but the 30-s run alone takes 30
    p.finish(jobs[0], wall=20.0)  # twice as slow as expected
    assert p.eta_seconds() == 60.0
    p.fraction[jobs[1].path] = 0.5
    assert p.eta_seconds() == 30.0 and p.eta_text() == "ETA 0:00:30"
    many = [_job("a", f"v{k}") for k in range(4)]
    assert Progress(many, "t", {j.path: 10.0 for j in many}, workers=2).eta_seconds() == 20.0
    q = Progress(jobs, "t", {jobs[0].path: 10.0, jobs[1].path: 30.0}, workers=2, calibrated=False)
    assert q.eta_seconds() is None and q.eta_text() == ""  # relative weights only: no ETA before a run ends


def test_one_pool_starts_the_longest_runs_first_and_gives_each_experiment_its_own_numbers(tmp_path, monkeypatch):
    specs = [get_experiment("td-depth"), get_experiment("pole-full")]
    table = {"profile": "tiny", "seconds": {"pole-full": {v.label: 5.0 for v in specs[1].variants},
                                            "td-depth": {v.label: 1.0 for v in specs[0].variants}}}
    monkeypatch.setattr(timing, "load_run_times", lambda path=timing.RUN_TIMES: table)
    done = []
    outcomes = run_experiments([Batch(s, "tiny", None, 0) for s in specs], out=tmp_path / "pool", workers=1,
                               show_progress=False, on_done=lambda o: done.append(o.summary["experiment"]))
    assert done == ["pole-full", "td-depth"]  # the longer experiment's runs went first, and it finished first
    starts = sorted((r["started_at"], r["experiment"]) for o in outcomes for r in o.records)
    assert [e for _, e in starts][0] == "pole-full"
    for spec, outcome in zip(specs, outcomes, strict=True):
        alone = run_experiment(spec, profile="tiny", seed=0, out=tmp_path / "alone", workers=1, show_progress=False)
        assert json.dumps(outcome.summary["variants"]) == json.dumps(alone.summary["variants"])
        assert (outcome.ran, outcome.reused) == (len(alone.records), 0)
    for o in outcomes:  # each experiment's wall time is its own runs' span, not the pool's
        spans = [timing.run_span(r) for r in o.records]
        assert o.summary["timing"]["wall_time_s"] == max(b for _, b in spans) - min(a for a, _ in spans)
    monkeypatch.setattr(runner, "RayExecutor", lambda *a, **k: pytest.fail("an executor started with nothing to run"))
    again = run_experiments([Batch(s, "tiny", None, 0) for s in specs], out=tmp_path / "pool", workers=1,
                            show_progress=False, executor="ray")
    assert [(o.ran, o.reused) for o in again] == [(0, len(o.records)) for o in outcomes]


def test_a_run_two_experiments_share_is_computed_once_and_copied(tmp_path, monkeypatch):
    # robot-dp-replay-order's "3 lessons, after" is robot-repairs-3's "none": same run function, parameters and seed
    specs = [get_experiment("robot-repairs-3"), get_experiment("robot-dp-replay-order")]
    pair = {("robot-repairs-3", "none"), ("robot-dp-replay-order", "3 lessons, after")}
    ran = []
    execute_job = runner.execute_job
    monkeypatch.setattr(runner, "execute_job", lambda job: ran.append(job.path) or execute_job(job))
    pooled = run_experiments([Batch(s, "tiny", None, 0) for s in specs], out=tmp_path / "pool", workers=1,
                             show_progress=False)
    assert len(ran) == sum(len(o.records) for o in pooled) - 1
    (copy,) = [r for o in pooled for r in o.records if r.get("copy_of")]
    source = (copy["copy_of"]["experiment"], copy["copy_of"]["variant"])
    assert {(copy["experiment"], copy["variant"]), source} == pair
    assert (tmp_path / "pool" / copy["copy_of"]["record"]).is_file()
    assert "copy_of" in check_record(dict(copy, copy_of="robot-repairs-3"))  # a damaged mark is reported
    e = timing.per_experiment([copy])[copy["experiment"]]
    assert (e["runs"], e["copies"], e["run_s"]) == (0, 1, 0.0)  # its time was spent once, in the run it copies
    monkeypatch.setattr(runner, "execute_job", execute_job)
    spec = get_experiment(copy["experiment"])
    alone = run_experiment(spec, profile="tiny", seed=0, out=tmp_path / "alone", workers=1, show_progress=False)
    pooled_summary = next(o.summary for o in pooled if o.summary["experiment"] == spec.name)
    assert json.dumps(pooled_summary["variants"]) == json.dumps(alone.summary["variants"])
    for p in (tmp_path / "pool" / spec.name).rglob("seed-*.csv"):
        assert p.read_bytes() == (tmp_path / "alone" / p.relative_to(tmp_path / "pool")).read_bytes()
    again = run_experiments([Batch(s, "tiny", None, 0) for s in specs], out=tmp_path / "pool", workers=1,
                            show_progress=False)
    assert [o.ran for o in again] == [0, 0]  # a copy is a finished run like any other
