"""Run an experiment: independent runs (variant x seed) in parallel processes, stored atomically, resumable.

Layout of ``OUT/NAME/``::

    summary.json                   every reproduced quantity: per-run values, mean, the thesis's value
    curve.png, curve.svg           learning curves, mean and spread over runs (``connrl.report.plots``)
    runs/PROFILE-HASH/VARIANT/seed-S.csv   the run's learning curve and rows
    runs/PROFILE-HASH/VARIANT/seed-S.json  metadata: params, seed, versions, git commit, wall time, metrics

A run whose ``.json`` exists is finished and is not redone, so a run interrupted with Ctrl-C resumes where it
stopped. The executor sits behind ``Executor`` (``map_unordered``), so another backend (e.g. Ray) can run the
same jobs elsewhere.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import multiprocessing as mp
import os
import platform
import queue
import re
import subprocess
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from connrl.experiments.spec import ExperimentSpec, RunResult, as_dict, load_callable, qualified_name
from connrl.storage import atomic_write_text


@dataclass(frozen=True)
class Job:
    """One independent run."""

    experiment: str
    run_ref: str  # "module:function"
    variant: str
    params: dict  # plain data (stored in the record); the run function gets an instance of params_type
    seed: int
    path: str  # where its records go (without suffix)
    params_type: str  # "module:Class" of the spec's parameter dataclass


def variant_slug(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.=-]+", "_", label).strip("_") or "default"


def params_hash(params: dict) -> str:
    return hashlib.sha256(json.dumps(params, sort_keys=True, default=str).encode()).hexdigest()[:10]


def make_jobs(spec: ExperimentSpec, profile: str, runs: int | None, seed: int, out: Path) -> list[Job]:
    base, n = spec.resolve(profile, runs)
    root = out / spec.name / "runs" / f"{profile}-{params_hash(as_dict(base))}"
    jobs = []
    for v in spec.variants:
        params = as_dict(spec.variant_params(base, v))
        for i in range(n):
            # seed s + i for run i: variants share seeds (common random numbers for comparisons)
            s = seed + i
            path = root / variant_slug(v.label) / f"seed-{s}"
            jobs.append(Job(spec.name, spec.run, v.label, params, s, str(path), qualified_name(spec.params)))
    return jobs


# ------------------------------------------------------------------------------------------- executors

class Executor(Protocol):
    """Runs ``fn(job)`` for every job, yields ``(job, result)`` as each finishes, calls ``tick()`` often."""

    def map_unordered(self, fn: Callable, jobs: list[Job],
                      tick: Callable[[], None]) -> Iterator[tuple[Job, Any]]: ...


_progress_queue = None
_progress_tick: Callable[[], None] | None = None


def _init_worker(q, tick=None):
    global _progress_queue, _progress_tick
    _progress_queue, _progress_tick = q, tick


def execute_job(job: Job) -> dict:
    """Run one job in this process and write its records; returns the metadata record."""
    fn = load_callable(job.run_ref)
    params = load_callable(job.params_type)(**job.params)
    rng = np.random.default_rng(job.seed)
    last = [0.0]

    def progress(done, total):
        now = time.monotonic()
        if _progress_queue is not None and (now - last[0] > 0.2 or done >= total):
            last[0] = now
            _progress_queue.put((job.path, done, total))
            if _progress_tick is not None:
                _progress_tick()

    t0 = time.perf_counter()
    result: RunResult = fn(params, rng, progress)
    wall = time.perf_counter() - t0
    record = {
        "experiment": job.experiment,
        "variant": job.variant,
        "seed": job.seed,
        "params": job.params,
        "metrics": result.metrics,
        "curve_x": [float(v) for v in result.curve_x],
        "curve_y": [float(v) for v in result.curve_y],
        "extra": result.extra,
        "environment": environment_info(),
        "wall_time_s": wall,
    }
    write_run_records(Path(job.path), record, result.rows)
    return record


class SerialExecutor:
    """Runs jobs one after another in this process (used with --workers 1 and in tests)."""

    def __init__(self, progress_queue=None):
        self.q = progress_queue

    def map_unordered(self, fn, jobs, tick):
        _init_worker(self.q, tick)
        try:
            for job in jobs:
                yield job, fn(job)
        finally:
            _init_worker(None)


class ProcessExecutor:
    """Independent runs in worker processes (default: one per core)."""

    def __init__(self, workers: int, progress_queue=None):
        self.workers = workers
        self.q = progress_queue

    def map_unordered(self, fn, jobs, tick):
        ctx = mp.get_context("spawn")  # fresh interpreters: no inherited state, same on every OS
        pool = ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=_init_worker, initargs=(self.q,))
        pending: dict[Future, Job] = {}
        it = iter(jobs)
        try:
            for job in it:
                pending[pool.submit(fn, job)] = job
                if len(pending) >= 2 * self.workers:
                    break
            while pending:
                done, _ = wait(pending, timeout=0.25, return_when=FIRST_COMPLETED)
                tick()
                for fut in done:
                    job = pending.pop(fut)
                    yield job, fut.result()
                    nxt = next(it, None)
                    if nxt is not None:
                        pending[pool.submit(fn, nxt)] = nxt
        finally:
            for fut in pending:
                fut.cancel()
            pool.shutdown(wait=True, cancel_futures=True)


# ------------------------------------------------------------------------------------------------ store

def write_run_records(path: Path, record: dict, rows: list[dict]) -> None:
    buf = io.StringIO()
    if rows:
        keys = list(dict.fromkeys(k for r in rows for k in r))
        w = csv.DictWriter(buf, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    else:
        w = csv.writer(buf)
        w.writerow(["x", "y"])
        w.writerows(zip(record["curve_x"], record["curve_y"], strict=True))
    atomic_write_text(path.with_suffix(".csv"), buf.getvalue())
    # the .json is written last: its presence marks the run as finished
    atomic_write_text(path.with_suffix(".json"), json.dumps(record, indent=1, default=_json_default))


def _json_default(o):
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"cannot store {type(o).__name__} in JSON")


def load_record(job: Job) -> dict | None:
    p = Path(job.path).with_suffix(".json")
    if not p.exists():
        return None
    try:
        return json.loads(p.read_text())
    except json.JSONDecodeError:
        return None  # a damaged record is redone


_ENV_INFO: dict | None = None


def environment_info() -> dict:
    global _ENV_INFO
    if _ENV_INFO is None:
        import gymnasium
        import numba

        import connrl

        try:
            commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5,
                                    cwd=Path(__file__).parent).stdout.strip() or None
        except (OSError, subprocess.SubprocessError):
            commit = None
        _ENV_INFO = {"python": platform.python_version(), "numpy": np.__version__, "numba": numba.__version__,
                     "gymnasium": gymnasium.__version__, "connrl": connrl.__version__, "git_commit": commit,
                     "machine": platform.machine(), "cpus": os.cpu_count()}
    return _ENV_INFO


# ---------------------------------------------------------------------------------------------- summary

def summarize(spec: ExperimentSpec, profile: str, seed: int, records: list[dict], wall: float) -> dict:
    """summary.json: per variant and quantity, the per-run values (in seed order), mean and thesis value."""
    by_variant: dict[str, list[dict]] = {v.label: [] for v in spec.variants}
    for r in sorted(records, key=lambda r: r["seed"]):
        by_variant[r["variant"]].append(r)
    variants = {}
    for v in spec.variants:
        recs = by_variant[v.label]
        qs = {}
        for q in spec.quantities:
            vals = [r["metrics"].get(q.name) for r in recs]
            finite = [x for x in vals if x is not None and np.isfinite(x)]
            qs[q.name] = {
                "description": q.description,
                "per_run": vals,
                "mean": float(np.mean(finite)) if finite else None,
                "std": float(np.std(finite)) if finite else None,
                "runs_reaching": len(finite),
                "thesis": v.thesis.get(q.name),
                "better": q.better,
                "section": q.section or spec.section,
            }
            t = v.thesis.get(q.name)
            m = qs[q.name]["mean"]
            if t is not None and m is not None and len(finite) == len(vals):
                qs[q.name]["meets_thesis"] = bool(m <= t if q.better == "lower" else m >= t)
            elif t is not None:
                qs[q.name]["meets_thesis"] = False if len(finite) < len(vals) else None
        variants[v.label] = {"seeds": [r["seed"] for r in recs], "params": v.params and dict(v.params),
                             "quantities": qs}
    return {
        "experiment": spec.name,
        "title": spec.title,
        "section": spec.section,
        "profile": profile,
        "base_seed": seed,
        "runs_per_variant": len(records) // max(len(spec.variants), 1),
        "variants": variants,
        "environment": dict(environment_info()),
        "timing": {"wall_time_s": wall,
                   "run_wall_time_s": [r["wall_time_s"] for r in sorted(records, key=lambda r: (r["variant"],
                                                                                                r["seed"]))]},
    }


# -------------------------------------------------------------------------------------------------- run

@dataclass
class RunOutcome:
    summary: dict
    summary_path: Path
    records: list[dict]
    ran: int
    reused: int


def run_experiment(spec: ExperimentSpec, *, profile: str = "quick", runs: int | None = None, seed: int = 0,
                   out: Path | str = "runs", workers: int | None = None,
                   show_progress: bool = True) -> RunOutcome:
    out = Path(out)
    jobs = make_jobs(spec, profile, runs, seed, out)
    records, todo = [], []
    for job in jobs:
        rec = load_record(job)
        (records.append(rec) if rec is not None else todo.append(job))
    reused = len(records)
    workers = workers or os.cpu_count() or 1
    t0 = time.perf_counter()
    if todo:
        records.extend(_execute(todo, min(workers, len(todo)), show_progress, spec.name))
    wall = time.perf_counter() - t0
    summary = summarize(spec, profile, seed, records, wall)
    summary_path = out / spec.name / "summary.json"
    atomic_write_text(summary_path, json.dumps(summary, indent=1, default=_json_default))
    return RunOutcome(summary, summary_path, records, len(todo), reused)


def _execute(jobs: list[Job], workers: int, show_progress: bool, title: str) -> list[dict]:
    manager = mp.get_context("spawn").Manager() if (show_progress and workers > 1) else None
    q = manager.Queue() if manager is not None else (queue.SimpleQueue() if show_progress else None)
    executor: Executor = ProcessExecutor(workers, q) if workers > 1 else SerialExecutor(q)
    results = []
    display = _Progress(jobs, title) if show_progress else None

    def tick():
        if display:
            display.drain(q)

    try:
        if display:
            display.start()
        for job, rec in executor.map_unordered(execute_job, jobs, tick):
            results.append(rec)
            tick()
            if display:
                display.finish(job)
    finally:
        if display:
            display.stop()
        if manager is not None:
            manager.shutdown()
    return results


class _Progress:
    """A rich live display: one bar for the experiment, one per run in flight."""

    def __init__(self, jobs: Iterable[Job], title: str):
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        self.jobs = {j.path: j for j in jobs}
        self.progress = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                                 TimeElapsedColumn(), transient=False)
        self.total = self.progress.add_task(f"{title}: runs", total=len(self.jobs))
        self.tasks: dict[str, int] = {}

    def start(self):
        self.progress.start()

    def stop(self):
        self.progress.stop()

    def drain(self, q):
        if q is None:
            return
        while True:
            try:
                path, done, total = q.get_nowait()
            except (queue.Empty, EOFError, OSError):
                return
            if path not in self.jobs:
                continue
            if path not in self.tasks:
                j = self.jobs[path]
                self.tasks[path] = self.progress.add_task(f"  {j.variant} seed {j.seed}", total=total)
            self.progress.update(self.tasks[path], completed=done, total=total)

    def finish(self, job: Job):
        self.progress.advance(self.total)
        if job.path in self.tasks:
            self.progress.remove_task(self.tasks.pop(job.path))


def stored_runs(spec: ExperimentSpec, out: Path) -> tuple[dict | None, list[dict]]:
    """The summary of the latest ``connrl run`` of ``spec`` under ``out`` and the run records it names."""
    p = Path(out) / spec.name / "summary.json"
    if not p.exists():
        return None, []
    summary = json.loads(p.read_text())
    jobs = make_jobs(spec, summary["profile"], summary["runs_per_variant"], summary["base_seed"], Path(out))
    return summary, [r for r in (load_record(j) for j in jobs) if r is not None]
