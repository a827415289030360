"""How fast the whole thesis could be with every line of Python gone: the time its compiled (Numba) kernels take.

For every variant of every experiment, one of its stored runs (the one of median run time) is run again under
cProfile in a worker process; the kernels' own time (each Numba dispatcher's calls, which cProfile times as one
call each, so hardly slowed) over the run's stored time is the variant's compiled share. The variant's stored run
time times that share is its kernel time; summed, the thesis's kernel floor, the time no Python work can remove.

    python benchmarks/kernel_floor.py --out /tmp/thesis-full --workers 2 --write docs/PERFORMANCE.md

``--out`` is a folder of full-profile records made by one `connrl reproduce` (their times are the run times the
floor is taken of). The first run in each worker also loads the cached kernels, which counts as kernel time.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from statistics import median

from blocks import paste

from connrl.experiments.registry import all_experiments, by_chapter, chapters
from connrl.experiments.runner import make_jobs, run_job, stored_runs
from connrl.experiments.timing import computed


def kernel_code_keys() -> set[tuple[str, int, str]]:
    """cProfile's (file, line, name) of every Numba dispatcher in the loaded connrl modules."""
    from numba.core.registry import CPUDispatcher

    keys = set()
    for mod_name, mod in list(sys.modules.items()):
        if not mod_name.startswith("connrl") or mod is None:
            continue
        for obj in vars(mod).values():
            if isinstance(obj, CPUDispatcher):
                code = obj.py_func.__code__
                keys.add((code.co_filename, code.co_firstlineno, code.co_name))
    return keys


def kernel_seconds(name: str, variant: str, seed: int, profile: str) -> float:
    """Seconds inside compiled kernels of one run, profiled in this process."""
    spec = all_experiments()[name]
    jobs = make_jobs(spec, profile, spec.full_runs if profile == "full" else None, spec.seed, Path("/nonexistent"))
    job = next(j for j in jobs if j.variant == variant and j.seed == seed)
    prof = cProfile.Profile()
    prof.enable()
    run_job(job)
    prof.disable()
    keys = kernel_code_keys()
    return sum(st[2] for key, st in pstats.Stats(prof).stats.items() if key in keys)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="a folder of full-profile records from one reproduce")
    ap.add_argument("--profile", default="full")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--write", type=Path, default=None, help="paste the table into this Markdown file's block")
    args = ap.parse_args()
    specs = all_experiments()
    picks = []  # (experiment, variant, seed, the run's time, the variant's total time)
    for name, spec in specs.items():
        summary, recs = stored_runs(spec, Path(args.out))
        if summary is None or summary["profile"] != args.profile:
            continue
        recs = computed(recs)  # a copy of a twin run took no time
        for variant in sorted({r["variant"] for r in recs}):
            rs = sorted((r for r in recs if r["variant"] == variant), key=lambda r: r["wall_time_s"])
            mid = rs[(len(rs) - 1) // 2]
            picks.append((name, variant, mid["seed"], mid["wall_time_s"], sum(r["wall_time_s"] for r in rs)))
    picks.sort(key=lambda p: -p[3])
    with ProcessPoolExecutor(args.workers) as pool:
        kernel = list(pool.map(kernel_seconds, *zip(*[(p[0], p[1], p[2], args.profile) for p in picks], strict=True)))
    text = report(picks, kernel, args)
    print(text)
    if args.write:
        paste(args.write, "kernel_floor", how_called(args), text, fenced=False)


def how_called(args) -> str:
    return f"python benchmarks/kernel_floor.py --out {args.out} --profile {args.profile} --workers {args.workers}"


def report(picks, kernel, args) -> str:
    chapter_of = {spec.name: c for c in chapters() for spec in by_chapter([c])}
    per_chapter: dict[int, list[float]] = {}
    for (name, _, _, run_s, total_s), k in zip(picks, kernel, strict=True):
        share = min(k / run_s, 1.0) if run_s > 0 else 0.0
        row = per_chapter.setdefault(chapter_of[name], [0.0, 0.0])
        row[0] += total_s
        row[1] += total_s * share
    shares = [min(k / p[3], 1.0) for p, k in zip(picks, kernel, strict=True) if p[3] > 0]
    lines = [f"{len(picks)} variants, one run each (its median-time run) under cProfile; compiled share of a variant's "
             f"runs: median {median(shares):.0%}, range {min(shares):.0%}-{max(shares):.0%}.", "",
             "| chapter | run time (CPU-min) | in compiled kernels (CPU-min) | share | kernels over 2 cores (min) |",
             "|---|---|---|---|---|"]
    all_run = all_kernel = 0.0
    for chapter in sorted(per_chapter):
        run_s, kernel_s = per_chapter[chapter]
        all_run += run_s
        all_kernel += kernel_s
        lines.append(f"| {chapter} | {run_s / 60:.1f} | {kernel_s / 60:.1f} | {kernel_s / run_s:.0%} | "
                     f"{kernel_s / 120:.1f} |")
    lines.append(f"| all | {all_run / 60:.1f} | {all_kernel / 60:.1f} | {all_kernel / all_run:.0%} | "
                 f"{all_kernel / 120:.1f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
