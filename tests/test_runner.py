"""Runner: determinism, resume after interruption, atomic records, summary.json contents, parallel workers."""

import json

import numpy as np
import pytest

from connrl.experiments import runner
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant


def toy_run(params, rng, progress):
    draws = rng.random(params["n"])
    progress(params["n"], params["n"])
    return RunResult(list(range(params["n"])), list(np.cumsum(draws)), {"total": float(draws.sum())},
                     rows=[{"i": i, "draw": float(d)} for i, d in enumerate(draws)])


CALLS = []


def counting_run(params, rng, progress):
    CALLS.append(params["n"])
    if params.get("explode_at") == len(CALLS):
        raise KeyboardInterrupt
    return toy_run(params, rng, progress)


def spec(run="tests.test_runner:toy_run"):
    return ExperimentSpec(
        name="toy", title="toy", section="-", run=run, params={"n": 5},
        profiles={"tiny": {"runs": 2}, "quick": {"runs": 3}, "full": {"runs": 4, "n": 7}},
        variants=(Variant("a", {}, {"total": 2.0}), Variant("b/c", {"n": 6})),
        quantities=(Quantity("total", "sum of draws", "higher"),))


def strip_timing(summary):
    return {k: v for k, v in summary.items() if k != "timing"}


def test_same_seed_same_summary_and_layout(tmp_path):
    o1 = runner.run_experiment(spec(), profile="tiny", seed=4, out=tmp_path / "1", workers=1, show_progress=False)
    o2 = runner.run_experiment(spec(), profile="tiny", seed=4, out=tmp_path / "2", workers=1, show_progress=False)
    assert strip_timing(o1.summary) == strip_timing(o2.summary)
    s = json.loads(o1.summary_path.read_text())
    q = s["variants"]["a"]["quantities"]["total"]
    assert len(q["per_run"]) == 2 and q["thesis"] == 2.0 and s["variants"]["a"]["seeds"] == [4, 5]
    assert (tmp_path / "1" / "toy" / "curve.png").exists() and (tmp_path / "1" / "toy" / "curve.svg").exists()
    csvs = sorted(p.name for p in (tmp_path / "1" / "toy").rglob("seed-*.csv"))
    assert csvs == ["seed-4.csv", "seed-4.csv", "seed-5.csv", "seed-5.csv"]
    meta = json.loads(next((tmp_path / "1" / "toy").rglob("seed-4.json")).read_text())
    assert meta["seed"] == 4 and "git_commit" in meta["environment"] and meta["wall_time_s"] >= 0


def test_different_seed_differs(tmp_path):
    a = runner.run_experiment(spec(), profile="tiny", seed=0, out=tmp_path, workers=1, show_progress=False)
    b = runner.run_experiment(spec(), profile="tiny", seed=1, out=tmp_path, workers=1, show_progress=False)
    assert a.summary["variants"]["a"]["quantities"]["total"]["per_run"] != \
        b.summary["variants"]["a"]["quantities"]["total"]["per_run"]


def test_interrupted_run_keeps_finished_runs_and_resumes(tmp_path):
    CALLS.clear()
    s = spec("tests.test_runner:counting_run")
    interrupted = ExperimentSpec(**{**s.__dict__, "params": {"n": 5, "explode_at": 3}})
    with pytest.raises(KeyboardInterrupt):
        runner.run_experiment(interrupted, profile="tiny", out=tmp_path, workers=1, show_progress=False)
    done = list((tmp_path / "toy").rglob("seed-*.json"))
    assert len(done) == 2  # the two finished runs were written
    CALLS.clear()
    out = runner.run_experiment(interrupted, profile="tiny", out=tmp_path, workers=1, show_progress=False)
    assert out.reused == 2 and out.ran == 2 and len(CALLS) == 2
    assert not list((tmp_path / "toy").rglob("*.tmp"))


def test_parallel_workers_give_the_same_numbers(tmp_path):
    serial = runner.run_experiment(spec(), profile="tiny", out=tmp_path / "s", workers=1, show_progress=False)
    par = runner.run_experiment(spec(), profile="tiny", out=tmp_path / "p", workers=2, show_progress=False)
    assert strip_timing(serial.summary) == strip_timing(par.summary)


def test_runs_override_and_unknown_profile():
    assert spec().resolve("full") == ({"n": 7}, 4)
    assert spec().resolve("quick", runs=9)[1] == 9
    with pytest.raises(ValueError, match="unknown profile 'huge'; allowed: tiny, quick, full"):
        spec().resolve("huge")


def test_spec_requires_every_profile():
    with pytest.raises(ValueError, match="missing"):
        ExperimentSpec(name="x", title="x", section="-", run="m:f", params={}, profiles={"tiny": {"runs": 1}},
                       variants=(), quantities=())
