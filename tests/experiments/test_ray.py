"""``--executor ray``: the same per-run values and records as the process pool, on a local Ray instance; refusals."""

import json
from pathlib import Path

import pytest

from connrl.experiments.registry import get_experiment
from connrl.experiments.runner import check_executor, make_jobs, run_experiment


def _per_run(summary):
    return {v: {q: x["per_run"] for q, x in d["quantities"].items()} for v, d in summary["variants"].items()}


def test_ray_tasks_give_the_process_pools_values(tmp_path):
    pytest.importorskip("ray")
    spec = get_experiment("cup-task1")  # one run per variant on the tiny profile: seven independent runs
    by_ray = run_experiment(spec, profile="tiny", out=tmp_path / "ray", workers=2, show_progress=False,
                            executor="ray")
    by_pool = run_experiment(spec, profile="tiny", out=tmp_path / "pool", workers=2, show_progress=False)
    assert by_ray.ran == by_pool.ran == len(spec.variants) > 1
    assert _per_run(by_ray.summary) == _per_run(by_pool.summary)
    for job in make_jobs(spec, "tiny", None, 0, tmp_path / "pool"):  # the driver wrote every run's records
        pool = Path(job.path)
        ray = tmp_path / "ray" / pool.relative_to(tmp_path / "pool")
        assert ray.with_suffix(".csv").read_text() == pool.with_suffix(".csv").read_text()
        assert json.loads(ray.with_suffix(".json").read_text())["metrics"] == \
            json.loads(pool.with_suffix(".json").read_text())["metrics"]


def test_unknown_executor_and_missing_ray_are_one_line(monkeypatch):
    with pytest.raises(ValueError, match="unknown executor 'dask'; available: process, ray"):
        check_executor("dask")
    import importlib.util
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: None)
    with pytest.raises(ValueError, match=r'--executor ray needs Ray: pip install -e "\.\[ray\]"'):
        check_executor("ray")
