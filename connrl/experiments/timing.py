"""How long runs take: the expected time of each run (to start the longest first and to give an ETA), and where a
pool of runs spent its time (``benchmarks/thesis_time.py``'s table in docs/PERFORMANCE.md).

The expected times are ``connrl/data/run_times.json``: each experiment's and variant's mean run time at the full
profile, measured by ``python benchmarks/thesis_time.py ... --write-times`` on the 2-core development machine.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from statistics import median

RUN_TIMES = Path(__file__).resolve().parents[1] / "data" / "run_times.json"


def job_profile(job) -> str:
    """The profile a job runs at, read off its path (``.../runs/PROFILE-HASH/VARIANT/seed-S``)."""
    return Path(job.path).parent.parent.name.split("-")[0]


def load_run_times(path: Path = RUN_TIMES) -> dict:
    try:
        table = json.loads(Path(path).read_text())
        return table if isinstance(table.get("seconds"), dict) else {"profile": None, "seconds": {}}
    except (OSError, ValueError, AttributeError):  # no table (or a damaged one) only costs the ordering and the ETA
        return {"profile": None, "seconds": {}}


def expected_seconds(jobs: Iterable, table: dict | None = None) -> tuple[dict[str, float], bool]:
    """Each job's expected seconds (by path) and whether they are seconds of this machine's kind (the table's profile
    is every job's) or only relative weights. A variant the table lacks gets its experiment's median, an experiment
    it lacks the median of all."""
    table = load_run_times() if table is None else table
    seconds = table.get("seconds", {})
    every = [s for variants in seconds.values() for s in variants.values()]
    overall = median(every) if every else 1.0
    out, calibrated = {}, True
    for job in jobs:
        variants = seconds.get(job.experiment, {})
        out[job.path] = float(variants.get(job.variant, median(variants.values()) if variants else overall))
        calibrated &= job_profile(job) == table.get("profile")
    return out, calibrated


def run_times_table(records: Iterable[dict], profile: str, made_by: str) -> dict:
    """The table ``expected_seconds`` reads, from run records: the mean run time per experiment and variant."""
    sums: dict[str, dict[str, list[float]]] = {}
    for r in records:
        sums.setdefault(r["experiment"], {}).setdefault(r["variant"], []).append(float(r["wall_time_s"]))
    seconds = {e: {v: round(sum(t) / len(t), 3) for v, t in sorted(vs.items())} for e, vs in sorted(sums.items())}
    return {"profile": profile, "made_by": made_by, "seconds": seconds}


def computed(records: Iterable[dict]) -> list[dict]:
    """The records of runs computed, not copied from a twin (``connrl.experiments.store.write_copy``): their time
    was spent once, in the run they copy."""
    return [r for r in records if not r.get("copy_of")]


def run_span(rec: dict) -> tuple[float, float]:
    """(start, end) of a run in Unix seconds: its compiling counts, it kept a core busy (0-based for a record from
    before runs noted their start)."""
    start = float(rec.get("started_at", 0.0))
    return start, start + float(rec["wall_time_s"]) + float(rec.get("compile_time_s") or 0.0)


def pool_usage(records: list[dict], workers: int, start: float, end: float) -> dict:
    """Where the cores of a pool sat idle between ``start`` and ``end`` (Unix seconds; records need ``started_at``).

    ``busy_s`` is the core-seconds spent in runs, ``idle_s`` the rest of ``workers * (end - start)``; ``head_s`` is the
    time before the first run began (imports, refusals, reading what is stored), ``tail_s`` the time after fewer than
    ``workers`` runs were left in flight for good (the pool's tail: the last long runs), ``tail_idle_s`` the
    core-seconds idle in it."""
    spans = sorted(run_span(r) for r in computed(records))
    wall = max(end - start, 1e-9)
    busy = sum(b - a for a, b in spans)
    if not spans:
        return {"wall_s": wall, "busy_s": 0.0, "idle_s": workers * wall, "head_s": wall, "tail_s": 0.0,
                "tail_idle_s": 0.0, "utilisation": 0.0}
    # the last moment at which `workers` runs were in flight at once
    events = sorted([(a, 1) for a, _ in spans] + [(b, -1) for _, b in spans])
    running, full_until = 0, spans[0][0]
    for t, step in events:
        if step < 0 and running == workers:
            full_until = t
        running += step
    last_end = max(b for _, b in spans)
    tail_busy = sum(max(0.0, b - max(a, full_until)) for a, b in spans)
    tail = max(end, last_end) - full_until
    tail_idle = workers * tail - tail_busy
    return {"wall_s": wall, "busy_s": busy, "idle_s": max(workers * wall - busy, 0.0), "head_s": spans[0][0] - start,
            "tail_s": tail, "tail_idle_s": max(tail_idle, 0.0), "utilisation": busy / (workers * wall)}


def per_experiment(records: Iterable[dict]) -> dict[str, dict]:
    """Per experiment: the runs it computed and their seconds (wall, CPU, compiling), the longest, and their span in
    the pool (``cpu_known`` False: some record did not note its CPU time, which then counts as its wall time);
    ``copies``: its runs copied from a twin run (store.write_copy), whose time counts where they ran."""
    out: dict[str, dict] = {}
    for r in records:
        e = out.setdefault(r["experiment"], {"runs": 0, "copies": 0, "run_s": 0.0, "cpu_s": 0.0, "compile_s": 0.0,
                                              "longest_s": 0.0, "first": float("inf"), "last": 0.0,
                                              "cpu_known": True})
        if r.get("copy_of"):
            e["copies"] += 1
            continue
        a, b = run_span(r)
        e["runs"] += 1
        e["run_s"] += float(r["wall_time_s"])
        e["cpu_s"] += float(r.get("cpu_time_s", r["wall_time_s"]))
        e["cpu_known"] &= "cpu_time_s" in r  # records from before issue 45 did not note it
        e["compile_s"] += float(r.get("compile_time_s") or 0.0)
        e["longest_s"] = max(e["longest_s"], float(r["wall_time_s"]))
        e["first"], e["last"] = min(e["first"], a), max(e["last"], b)
    return out
