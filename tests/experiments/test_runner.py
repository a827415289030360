"""Runner: determinism, resume after interruption, atomic records, summary.json contents, parallel workers."""

import dataclasses
import json

import pytest

from connrl.experiments import runner
from connrl.report.plots import plot_experiment
from tests.experiments.toy import CALLS, ToyParams, spec


def strip_timing(summary):
    return {k: v for k, v in summary.items() if k != "timing"}


def test_same_seed_same_summary_and_layout(tmp_path):
    o1 = runner.run_experiment(spec(), profile="tiny", seed=4, out=tmp_path / "1", workers=1, show_progress=False)
    o2 = runner.run_experiment(spec(), profile="tiny", seed=4, out=tmp_path / "2", workers=1, show_progress=False)
    assert strip_timing(o1.summary) == strip_timing(o2.summary)
    s = json.loads(o1.summary_path.read_text())
    q = s["variants"]["a"]["quantities"]["total"]
    assert len(q["per_run"]) == 2 and q["thesis"] == 2.0 and s["variants"]["a"]["seeds"] == [4, 5]
    assert not list((tmp_path / "1" / "toy").glob("curve.*"))  # the runner does not plot (the CLI does) ...
    plot_experiment(spec(), o1.records, tmp_path / "1" / "toy")  # ... from the records it returns
    assert (tmp_path / "1" / "toy" / "curve.png").exists() and (tmp_path / "1" / "toy" / "curve.svg").exists()
    csvs = sorted(p.name for p in (tmp_path / "1" / "toy").rglob("seed-*.csv"))
    assert csvs == ["seed-4.csv", "seed-4.csv", "seed-5.csv", "seed-5.csv"]
    meta = json.loads(next((tmp_path / "1" / "toy").rglob("seed-4.json")).read_text())
    assert meta["seed"] == 4 and "git_commit" in meta["environment"] and meta["wall_time_s"] >= 0
    assert meta["params"] in ({"n": 5, "explode_at": None}, {"n": 6, "explode_at": None})  # plain data


def test_different_seed_differs(tmp_path):
    a = runner.run_experiment(spec(), profile="tiny", seed=0, out=tmp_path, workers=1, show_progress=False)
    b = runner.run_experiment(spec(), profile="tiny", seed=1, out=tmp_path, workers=1, show_progress=False)
    assert a.summary["variants"]["a"]["quantities"]["total"]["per_run"] != \
        b.summary["variants"]["a"]["quantities"]["total"]["per_run"]


def test_interrupted_run_keeps_finished_runs_and_resumes(tmp_path):
    CALLS.clear()
    counting = spec("tests.experiments.toy:counting_run")
    interrupted = dataclasses.replace(counting, params=ToyParams(explode_at=3))
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


def test_stored_runs_finds_the_records_again(tmp_path):
    out = runner.run_experiment(spec(), profile="tiny", seed=2, out=tmp_path, workers=1, show_progress=False)
    summary, records = runner.stored_runs(spec(), tmp_path)
    assert summary == out.summary
    key = lambda r: (r["variant"], r["seed"])  # noqa: E731
    assert sorted(records, key=key) == sorted(out.records, key=key)
    assert runner.stored_runs(spec(), tmp_path / "elsewhere") == (None, [])
