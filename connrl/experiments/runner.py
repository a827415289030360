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

import hashlib
import json
import multiprocessing as mp
import os
import queue
import re
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numba.core import event as numba_event

from connrl.core.divergence import Diverged
from connrl.experiments.guards import ExecutorError, check_ray_cluster, check_reachable, run_lock  # noqa: F401
from connrl.experiments.spec import ExperimentSpec, RunResult, as_dict, load_callable, qualified_name
from connrl.experiments.store import (
    DamagedFile,
    environment_info,
    json_default,
    load_record,
    load_summary,
    write_run_records,
)
from connrl.storage import atomic_write_text, strict_json


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


def remove_stale_temporaries(folder: Path) -> list[Path]:
    """Remove the temporary files (``.NAME.*.tmp``, ``connrl.storage``'s) a killed run left in ``folder``: those of
    the run records and the summary only, which only a run writes, and under the folder's lock, so no live writer's
    (a plot being redrawn meanwhile writes ``.curve.png.*.tmp``, which is left alone)."""
    gone = []
    for p in Path(folder).rglob(".*.tmp"):
        if p.name.startswith((".seed-", ".summary.json.")) and p.is_file() and not p.is_symlink():
            p.unlink(missing_ok=True)
            gone.append(p)
    return gone


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


def _init_worker(q, tick=None, parent: int | None = None):
    global _progress_queue, _progress_tick
    _progress_queue, _progress_tick = q, tick
    if parent is not None:
        threading.Thread(target=_exit_with_parent, args=(parent,), daemon=True).start()


def _exit_with_parent(parent: int) -> None:
    """A worker whose parent died (e.g. SIGKILL, which runs no cleanup) exits instead of running on: the
    parent is gone when this process has been handed to another (init or a subreaper)."""
    while True:
        time.sleep(0.5)
        if os.getppid() != parent:
            os._exit(1)


def execute_job(job: Job) -> dict:
    """Run one job in this process and write its records; returns the metadata record."""
    record, rows = run_job(job)
    write_run_records(Path(job.path), record, rows)
    return record


def run_job(job: Job) -> tuple[dict, list[dict]]:
    """Run one job in this process: (the metadata record, the CSV rows), nothing written (a Ray worker may be on
    another machine: the driver writes)."""
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
    diverged = None
    with numba_event.install_recorder("numba:compile") as compiles:
        try:
            result: RunResult = fn(params, rng, progress)
        except Diverged as exc:  # a failed run, recorded as such: its quantities are None, not "not reached"
            result, diverged = RunResult([], [], {}), {"trial": exc.trial, "reason": exc.reason}
    compile_s = compile_seconds(compiles.buffer)
    wall = time.perf_counter() - t0 - compile_s
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
        "wall_time_s": wall,  # without the Numba compiling the run triggered (the first run of a process pays it)
        "compile_time_s": compile_s,
        "diverged": diverged,
    }
    return record, result.rows


def compile_seconds(events) -> float:
    """Seconds spent compiling, from a ``numba:compile`` event recording (nested compiles counted once)."""
    total, depth, start = 0.0, 0, 0.0
    for t, ev in events:
        if ev.is_start:
            if depth == 0:
                start = t
            depth += 1
        elif depth:
            depth -= 1
            if depth == 0:
                total += t - start
    return total


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
        pool = ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=_init_worker,
                                   initargs=(self.q, None, os.getpid()))
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
        except BaseException:
            # Ctrl-C (or any error): stop the runs in flight instead of finishing them; what finished is saved
            procs = list(getattr(pool, "_processes", {}).values())  # no public handle on the workers
            for proc in procs:
                proc.terminate()
            for proc in procs:  # a worker that does not go within 5 s is killed: shutdown below waits for them all
                proc.join(timeout=5)
                if proc.is_alive():
                    proc.kill()
            raise
        finally:
            for fut in pending:
                fut.cancel()
            pool.shutdown(wait=True, cancel_futures=True)


class RayExecutor:
    """Runs as Ray tasks (``--executor ray``): on a local Ray instance started here, or on the cluster at ``address``
    (``ray start --head`` on one machine, ``ray start --address=HEAD:6379`` on the others; ``--address HEAD:6379``
    here). ``fn(job)`` runs as a task and its result comes back here (``_execute`` gives it ``run_job``, which writes
    nothing, and writes the records itself, so the cluster needs no shared disk)."""

    def __init__(self, workers: int, address: str | None = None):
        self.workers, self.address = workers, address

    def map_unordered(self, fn, jobs, tick):
        import ray

        started = not ray.is_initialized()
        if started and self.address:
            check_ray_cluster(self.address)  # answers, and takes this driver's token if it wants one
        if started:  # "local": a fresh instance here, whatever RAY_ADDRESS says; else the cluster at address
            try:
                ray.init(address=self.address or "local", num_cpus=None if self.address else self.workers,
                         include_dashboard=False, log_to_driver=False, configure_logging=False)
            except Exception as exc:  # unreachable address, a cluster refusing num_cpus, ...: one line
                raise ExecutorError(f"cannot start or reach Ray at {self.address or 'a local instance'}: "
                                    f"{type(exc).__name__}: {exc}") from None
        task = ray.remote(num_cpus=1)(fn)
        pending = {task.remote(job): job for job in jobs}
        try:
            while pending:
                done, _ = ray.wait(list(pending), num_returns=1, timeout=0.25)
                tick()
                for ref in done:
                    job = pending.pop(ref)
                    yield job, ray.get(ref)
        except BaseException:
            for ref in pending:  # Ctrl-C or an error: stop the runs in flight; what finished is saved
                ray.cancel(ref, force=True)
            raise
        finally:
            if started:
                ray.shutdown()


EXECUTORS = ("process", "ray")
def check_executor(executor: str) -> None:
    """Refuse an unknown executor, or Ray when it is not installed, in one line before any run."""
    if executor not in EXECUTORS:
        raise ValueError(f"unknown executor {executor!r}; available: {', '.join(EXECUTORS)}")
    if executor == "ray":
        import importlib.util
        if importlib.util.find_spec("ray") is None:
            raise ValueError("--executor ray needs Ray: pip install -e \".[ray]\" (or pip install ray)")


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
                             "quantities": qs,
                             # per run: the training trial after which its networks diverged, or None
                             "diverged": [(r.get("diverged") or {}).get("trial") for r in recs]}
    in_order = sorted(records, key=lambda r: (r["variant"], r["seed"]))
    return {
        "experiment": spec.name,
        "title": spec.title,
        "section": spec.section,
        "profile": profile,
        "base_seed": seed,
        "runs_per_variant": len(records) // max(len(spec.variants), 1),
        "protocol_runs": spec.profiles["full"]["runs"],  # runs per variant of the thesis's protocol
        "variants": variants,
        "environment": dict(environment_info()),
        "timing": {"wall_time_s": wall,
                   "run_compile_time_s": [r.get("compile_time_s", 0.0) for r in in_order],
                   "run_wall_time_s": [r["wall_time_s"] for r in in_order]},
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
                   out: Path | str = "runs", workers: int | None = None, show_progress: bool = True,
                   on_damaged: Callable[[Path, str], None] = lambda path, reason: None, executor: str = "process",
                   address: str | None = None) -> RunOutcome:
    """Run what is not stored yet and write summary.json; ``on_damaged(path, reason)`` hears of each damaged
    run record, which is redone. ``executor``: worker processes here ("process") or Ray tasks ("ray", on the cluster
    at ``address`` or a local instance)."""
    check_executor(executor)
    out = Path(out)
    jobs = make_jobs(spec, profile, runs, seed, out)
    prepare_outputs(out / spec.name, jobs)
    with run_lock(out / spec.name):
        remove_stale_temporaries(out / spec.name)
        records, todo = [], []
        for job in jobs:
            rec, damage = load_record(job.path, job)
            if damage:
                on_damaged(Path(job.path).with_suffix(".json"), damage)
            (records.append(rec) if rec is not None else todo.append(job))
        reused = len(records)
        workers = workers or os.cpu_count() or 1
        t0 = time.perf_counter()
        if todo:
            records.extend(_execute(todo, min(workers, len(todo)), show_progress, spec.name, executor, address))
        wall = time.perf_counter() - t0
        summary = summarize(spec, profile, seed, records, wall)
        summary_path = out / spec.name / "summary.json"
        atomic_write_text(summary_path, strict_json(summary, indent=1, default=json_default))
    return RunOutcome(summary, summary_path, records, len(todo), reused)


def _execute(jobs: list[Job], workers: int, show_progress: bool, title: str, kind: str = "process",
             address: str | None = None) -> list[dict]:
    # a plain queue handed to the workers when they start (no manager process that could outlive us); Ray's tasks
    # report no progress, only their end
    q = None if kind == "ray" or not show_progress else (
        mp.get_context("spawn").Queue() if workers > 1 else queue.SimpleQueue())
    executor: Executor = (RayExecutor(workers, address) if kind == "ray" else
                          ProcessExecutor(workers, q) if workers > 1 else SerialExecutor(q))
    results = []
    display = _Progress(jobs, title) if show_progress else None

    def tick():
        if display:
            display.drain(q)

    try:
        if display:
            display.start()
        for job, rec in executor.map_unordered(run_job if kind == "ray" else execute_job, jobs, tick):
            if kind == "ray":  # the task ran elsewhere: its records are written here
                rec, rows = rec
                write_run_records(Path(job.path), rec, rows)
            results.append(rec)
            tick()
            if display:
                display.finish(job)
    finally:
        if display:
            display.stop()
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


def prepare_outputs(folder: Path, jobs: list[Job]) -> None:
    """Make every folder the runs will write in, before any run: a path in the way fails now (``OSError``
    naming it), not after the compute."""
    for where in sorted({Path(j.path).parent for j in jobs}):
        try:
            where.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OSError(exc.errno, f"cannot write to {where}: {exc.strerror or exc}") from None
    in_the_way = [folder / name for name in ("summary.json", "curve.png", "curve.svg")]
    in_the_way += [Path(f"{j.path}{ext}") for j in jobs for ext in (".json", ".csv")]
    for p in in_the_way:
        if p.is_dir():
            raise IsADirectoryError(f"cannot write to {p}: a folder is in the way (move it and run again)")


def stored_runs(spec: ExperimentSpec, out: Path, on_damaged=None) -> tuple[dict | None, list[dict]]:
    """The summary of the latest ``connrl run`` of ``spec`` under ``out`` and the readable run records it
    names (damaged or missing ones are left out: compare with ``expected_runs``; ``on_damaged(path, reason)``
    hears of each damaged one). A damaged summary raises ``DamagedFile``."""
    p = Path(out) / spec.name / "summary.json"
    if not p.exists():
        return None, []
    summary = load_summary(p, spec.name)
    try:
        jobs = make_jobs(spec, summary["profile"], summary["runs_per_variant"], summary["base_seed"], Path(out))
    except ValueError as exc:
        raise DamagedFile(p, f"it does not fit experiment {spec.name}: {exc}") from None
    records = []
    for j in jobs:
        rec, damage = load_record(j.path, j)
        if damage and on_damaged is not None:
            on_damaged(Path(j.path).with_suffix(".json"), damage)
        if rec is not None:
            records.append(rec)
    return summary, records


def missing_runs(spec_name: str, summary: dict, records: list[dict]) -> str | None:
    """"N of the M runs in NAME's summary are missing or damaged", or None when every run was read."""
    expected = expected_runs(summary)
    if len(records) >= expected:
        return None
    return f"{expected - len(records)} of the {expected} runs in {spec_name}'s summary are missing or damaged"


def expected_runs(summary: dict) -> int:
    return sum(len(v.get("per_run", [])) for v in
               (next(iter(var["quantities"].values()), {}) for var in summary["variants"].values()))
