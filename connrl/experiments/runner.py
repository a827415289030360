"""Run an experiment: independent runs (variant x seed) in parallel processes, stored atomically, resumable.

Layout of ``OUT/NAME/``::

    summary.json                   every reproduced quantity: per-run values, mean, the thesis's value
    curve.png, curve.svg           learning curves, mean and spread over runs (``connrl.report.plots``)
    runs/PROFILE-HASH/VARIANT/seed-S.csv   the run's learning curve and rows
    runs/PROFILE-HASH/VARIANT/seed-S.json  metadata: params, seed, versions, git commit, wall time, metrics;
                                   ``copy_of`` when the run was copied from a twin (``split_twins``)

A run whose ``.json`` exists is finished and is not redone, so a run interrupted with Ctrl-C resumes where it
stopped. The executor sits behind ``Executor`` (``map_unordered``), so another backend (e.g. Ray) can run the
same jobs elsewhere.
"""

from __future__ import annotations

import contextlib
import json
import multiprocessing as mp
import os
import queue
import re
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from itertools import chain
from pathlib import Path

import numpy as np
from numba.core import event as numba_event

from connrl.core.divergence import Diverged
from connrl.experiments import executors
from connrl.experiments.executors import (  # noqa: F401 (the runner's API, as before they had a module of their own)
    EXECUTORS,
    Executor,
    ProcessExecutor,
    Progress,
    RayExecutor,
    SerialExecutor,
    check_executor,
)
from connrl.experiments.guards import ExecutorError, check_ray_cluster, check_reachable, run_lock  # noqa: F401
from connrl.experiments.spec import ExperimentSpec, RunResult, as_dict, load_callable, qualified_name, run_key
from connrl.experiments.store import (
    DamagedFile,
    environment_info,
    json_default,
    load_record,
    load_summary,
    write_copy,
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
    root = out / spec.name / "runs" / f"{profile}-{run_key(base)}"
    jobs = []
    for v in spec.variants:
        params = as_dict(spec.variant_params(base, v))
        for i in range(n):
            # seed s + i for run i: variants share seeds (common random numbers for comparisons)
            s = seed + i
            path = root / variant_slug(v.label) / f"seed-{s}"
            jobs.append(Job(spec.name, spec.run, v.label, params, s, str(path), qualified_name(spec.params)))
    return jobs


def adopt_earlier_folder(jobs: list[Job]) -> Path | None:
    """Rename to the jobs' run folder an earlier one of the same profile (named by an earlier key: before
    ``run_key``, a hash of every value) whose records all belong to these jobs, so stored runs are reused, not
    redone; returns the folder adopted (None: none fits, the folder is there already, or the rename failed: a second
    runner that lost the race finds the folder there). Only ``connrl run`` / ``reproduce`` adopt, never a reader such
    as ``connrl results``. A folder whose records hold every field of these jobs' parameters was written under
    ``run_key`` for other settings, and is left alone."""
    root = Path(jobs[0].path).parents[1]
    if root.exists() or not root.parent.is_dir():
        return None
    profile = root.name.split("-")[0]
    fields = set(jobs[0].params)
    for old in sorted(d for d in root.parent.glob(f"{profile}-*") if d.is_dir() and not d.is_symlink()):
        there = [(old / Path(j.path).relative_to(root), j) for j in jobs]
        found = [load_record(path, j) for path, j in there if path.with_suffix(".json").exists()]
        if found and all(rec is not None and not fields <= set(rec["params"]) for rec, _ in found):
            try:
                old.rename(root)
            except OSError:
                return None
            return old
    return None


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
        q = executors._progress_queue
        if q is not None and (now - last[0] > 0.2 or done >= total):
            last[0] = now
            q.put((job.path, done, total))
            if executors._progress_tick is not None:
                executors._progress_tick()

    started, t0, cpu0 = time.time(), time.perf_counter(), time.process_time()
    diverged = None
    with numba_event.install_recorder("numba:compile") as compiles:
        try:
            result: RunResult = fn(params, rng, progress)
        except Diverged as exc:  # a failed run, recorded as such: its quantities are None, not "not reached"
            result, diverged = RunResult([], [], {}), {"trial": exc.trial, "reason": exc.reason}
    compile_s = compile_seconds(compiles.buffer)
    wall = time.perf_counter() - t0 - compile_s
    cpu = time.process_time() - cpu0 - compile_s  # compiling is CPU-bound: its seconds come off both
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
        "cpu_time_s": max(cpu, 0.0),
        "started_at": started,  # Unix time at the worker: when the run began (benchmarks/thesis_time.py's pool timing)
        "pid": os.getpid(),
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
                   "run_wall_time_s": [r["wall_time_s"] for r in in_order],
                   # per run: copied from a twin run (store.write_copy), whose time was spent there
                   "run_copied": [bool(r.get("copy_of")) for r in in_order]},
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
    return run_experiments([Batch(spec, profile, runs, seed)], out=out, workers=workers, show_progress=show_progress,
                           on_damaged=on_damaged, executor=executor, address=address, title=spec.name)[0]


@dataclass(frozen=True)
class Batch:
    """One experiment's share of a pool: ``connrl run SPEC --profile PROFILE --runs RUNS --seed SEED``."""

    spec: ExperimentSpec
    profile: str
    runs: int | None
    seed: int


def run_experiments(batches: list[Batch], *, out: Path | str = "runs", workers: int | None = None,
                    show_progress: bool = True, on_damaged: Callable[[Path, str], None] = lambda path, reason: None,
                    executor: str = "process", address: str | None = None, title: str = "runs",
                    on_done: Callable[[RunOutcome], None] = lambda outcome: None) -> list[RunOutcome]:
    """Many experiments' runs as one pool, longest first (by ``connrl.experiments.timing``'s expected times), so no
    core waits on one experiment's last run while another's could start. Each experiment's summary.json is written
    (and ``on_done`` hears of it) as soon as its last run ends."""
    from connrl.experiments.timing import expected_seconds

    check_executor(executor)
    out = Path(out)
    plans = [(b, make_jobs(b.spec, b.profile, b.runs, b.seed, out)) for b in batches]
    for b, jobs in plans:
        prepare_outputs(out / b.spec.name, jobs)
    with contextlib.ExitStack() as locks:
        records: dict[str, list[dict]] = {}
        todo: list[Job] = []
        for b, jobs in plans:
            locks.enter_context(run_lock(out / b.spec.name))
            remove_stale_temporaries(out / b.spec.name)
            records[b.spec.name] = []
            for job in jobs:
                rec, damage = load_record(job.path, job)
                if damage:
                    on_damaged(Path(job.path).with_suffix(".json"), damage)
                (records[b.spec.name].append(rec) if rec is not None else todo.append(job))
        left = {b.spec.name: len(jobs) - len(records[b.spec.name]) for b, jobs in plans}
        reused = {name: len(recs) for name, recs in records.items()}
        outcomes: dict[str, RunOutcome] = {}
        t0 = time.perf_counter()

        def finish(b: Batch) -> None:
            recs = records[b.spec.name]
            ran = recs[reused[b.spec.name]:]  # this call's runs: its wall time is their span, not the pool's
            wall = (max(r["started_at"] + r["wall_time_s"] + r["compile_time_s"] for r in ran)
                    - min(r["started_at"] for r in ran)) if ran else time.perf_counter() - t0
            summary = summarize(b.spec, b.profile, b.seed, recs, wall)
            summary["timing"]["pooled"] = len(batches) > 1 and bool(ran)  # its wall time is a span in a shared pool
            summary_path = out / b.spec.name / "summary.json"
            atomic_write_text(summary_path, strict_json(summary, indent=1, default=json_default))
            outcomes[b.spec.name] = RunOutcome(summary, summary_path, recs, len(ran), reused[b.spec.name])
            on_done(outcomes[b.spec.name])

        for b, _ in plans:
            if left[b.spec.name] == 0:
                finish(b)
        expected, calibrated = expected_seconds(todo)
        todo.sort(key=lambda j: -expected[j.path])  # stable: equal times keep the experiments' order
        todo, twins = split_twins(todo)
        workers = min(workers or os.cpu_count() or 1, max(len(todo), 1))
        by_name = {b.spec.name: b for b in batches}
        for job, rec in (execute(todo, workers, show_progress, title, executor, address, expected, calibrated)
                         if todo else ()):
            # the run first, then its twins' copies, each written only once the one before is recorded
            for j, r in chain([(job, rec)], ((t, write_copy(Path(job.path), rec, t)) for t in twins.get(job.path, []))):
                records[j.experiment].append(r)
                left[j.experiment] -= 1
                if left[j.experiment] == 0:
                    finish(by_name[j.experiment])
    return [outcomes[b.spec.name] for b in batches]


def split_twins(jobs: list[Job]) -> tuple[list[Job], dict[str, list[Job]]]:
    """The jobs to run, and for each (by path) its twins: jobs of other experiments or variants with the same run
    function, parameters and seed, which would compute the same numbers (a run is a pure function of these; e.g.
    survival-speedup's QCON-M is survival-study2's). A twin's records are copied from the run, not computed again."""
    first: dict[str, Job] = {}
    twins: dict[str, list[Job]] = {}
    for job in jobs:
        key = json.dumps([job.run_ref, job.params_type, job.params, job.seed], sort_keys=True, default=json_default)
        if key in first:
            twins.setdefault(first[key].path, []).append(job)
        else:
            first[key] = job
    return list(first.values()), twins


def execute(jobs: list[Job], workers: int, show_progress: bool, title: str, kind: str = "process",
            address: str | None = None, expected: dict[str, float] | None = None,
            calibrated: bool = True) -> Iterator[tuple[Job, dict]]:
    """Run ``jobs`` (in the order given) and yield ``(job, record)`` as each finishes, its records written.
    ``expected`` (seconds by job path) drives the display's ETA."""
    # a plain queue handed to the workers when they start (no manager process that could outlive us); Ray's tasks
    # report no progress, only their end
    q = None if kind == "ray" or not show_progress else (
        mp.get_context("spawn").Queue() if workers > 1 else queue.SimpleQueue())
    pool: Executor = (RayExecutor(workers, address) if kind == "ray" else
                      ProcessExecutor(workers, q) if workers > 1 else SerialExecutor(q))
    display = Progress(jobs, title, expected, workers, calibrated and expected is not None) if show_progress else None

    def tick():
        if display:
            display.drain(q)

    try:
        if display:
            display.start()
        for job, rec in pool.map_unordered(run_job if kind == "ray" else execute_job, jobs, tick):
            if kind == "ray":  # the task ran elsewhere: its records are written here
                rec, rows = rec
                write_run_records(Path(job.path), rec, rows)
            tick()
            if display:
                display.finish(job, rec.get("wall_time_s"))
            yield job, rec
    finally:
        if display:
            display.stop()


def prepare_outputs(folder: Path, jobs: list[Job]) -> None:
    """Make every folder the runs will write in, before any run (an earlier key's folder of these runs is adopted
    first): a path in the way fails now (``OSError`` naming it), not after the compute."""
    adopt_earlier_folder(jobs)
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
