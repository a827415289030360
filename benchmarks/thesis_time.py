"""Time the whole thesis: `connrl reproduce` into a fresh --out, then where the time went, per experiment and per
chapter, and where the cores sat idle; optionally profile the most expensive experiments' longest runs.

    python benchmarks/thesis_time.py --out /tmp/thesis-full --profile full --write docs/PERFORMANCE.md --top 5
    python benchmarks/thesis_time.py --out results/thesis --from-records --write-times   # the ETA table

`--from-records` skips the run and reads what is stored (the pool's idle time is then unknown: the runs may come from
several commands). `--write-times` writes connrl/data/run_times.json (each variant's mean run time: the order runs start
in and the ETA of `connrl reproduce`). `--top N` runs the longest run of each of the N most expensive experiments again
(once to compile the uncached kernels, then) under cProfile, in this process, and splits its time into the compiled
trials (the loops that play a whole trial, Chs. 4-8), environment steps, action selection, learning (replay, updates,
models) and the rest (bookkeeping).
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import pstats
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

from blocks import paste

from connrl.experiments.registry import all_experiments, by_chapter, chapters
from connrl.experiments.runner import make_jobs, run_job, stored_runs
from connrl.experiments.timing import RUN_TIMES, computed, per_experiment, pool_usage, run_times_table

# cProfile's own-time of each function, by where it lives (the first pattern that matches the "file:function")
CATEGORIES = [
    # the compiled plays and trials of Chs. 4-8 (connrl/tasks/*_play.py, *_train.py): world steps, choices and on-line
    # updates in one kernel
    ("compiled trials", r"\(_(greedy|play|flat|learning|qcon|recurrent|model|window)_loop\)"),
    ("environment", r"connrl/envs/|gymnasium/|survival_models\.py:\d+\(predict|cup\.py"),
    ("action selection", r"exploration\.py|\((values|_mlp_values|_rotated_values|_forward_all|outputs|act|choose|"
                         r"q_values|applicable|select\w*)\)"),
    ("learning", r"replay|returns\.py|\((update|_update\w*|_bptt|_forward_sequence|train\w*|_momentum_step|learn|"
                 r"_rotated_update|_train|_single_layer\w*|relaxation_q|policy_mask|batch_targets)\)"),
]


def categorise(stats: pstats.Stats) -> dict[str, float]:
    out = {name: 0.0 for name, _ in CATEGORIES} | {"bookkeeping": 0.0}
    for (file, _, func), (_, _, tottime, _, _) in stats.stats.items():
        where = f"{file}:0({func})"
        name = next((n for n, pat in CATEGORIES if re.search(pat, where)), "bookkeeping")
        out[name] += tottime
    return out


def profile_run(spec, record: dict, profile: str) -> dict[str, float]:
    jobs = make_jobs(spec, profile, spec.full_runs if profile == "full" else None, spec.seed, Path("/nonexistent"))
    job = next(j for j in jobs if j.variant == record["variant"] and j.seed == record["seed"])
    run_job(job)  # first unprofiled: the uncached kernels compile, as in a pool worker before most of its runs
    prof = cProfile.Profile()
    prof.enable()
    run_job(job)
    prof.disable()
    return categorise(pstats.Stats(prof))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="the reproduce's output folder (fresh, unless --from-records)")
    ap.add_argument("--profile", default="full")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--from-records", action="store_true", help="read stored runs; run nothing")
    ap.add_argument("--write", type=Path, default=None, help="paste the table into this Markdown file's block")
    ap.add_argument("--block", default="thesis_time", help="the block's name (default thesis_time)")
    ap.add_argument("--write-times", action="store_true", help="write connrl/data/run_times.json")
    ap.add_argument("--top", type=int, default=0, help="profile the longest run of the N most expensive experiments")
    args = ap.parse_args()
    out = Path(args.out)
    wall = cpu = start = end = None
    if not args.from_records:
        if out.exists() and any(out.iterdir()):
            raise SystemExit(f"thesis_time: --out {out} is not empty; give a fresh folder (or --from-records)")
        cmd = [sys.executable, "-m", "connrl.cli", "reproduce", "--profile", args.profile, "--out", str(out),
               "--workers", str(args.workers), "--quiet"]
        start = time.time()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        end = time.time()
        wall = end - start
        use = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = use.ru_utime + use.ru_stime
    chapter_of: dict[str, int] = {}
    specs = all_experiments()
    records, order = [], []
    for chapter in chapters():
        for spec in by_chapter([chapter]):
            chapter_of[spec.name] = chapter
            summary, recs = stored_runs(spec, out)
            if summary is not None and summary["profile"] == args.profile:
                records += recs
                order.append(spec.name)
    if args.write_times:
        table = run_times_table(records, args.profile, how_called(args) + " --write-times")
        RUN_TIMES.write_text(json.dumps(table, indent=1) + "\n")
    lines = report(records, order, chapter_of, args, wall, cpu, start, end)
    if args.top:
        lines += profile_top(records, specs, args.top, args.profile)
    text = "\n".join(lines)
    print(text)
    if args.write:
        paste(args.write, args.block, how_called(args), text, fenced=False)


def how_called(args) -> str:
    return (f"python benchmarks/thesis_time.py --out {args.out} --profile {args.profile}"
            + (" --from-records" if args.from_records else f" --workers {args.workers}")
            + (f" --top {args.top}" if args.top else ""))


def report(records, order, chapter_of, args, wall, cpu, start, end) -> list[str]:
    per = per_experiment(records)
    total = sum(e["run_s"] for e in per.values())
    commits = sorted({(r.get("environment") or {}).get("git_commit", "?")[:7] for r in records})
    copies = len(records) - len(computed(records))
    lines = [f"On {os.cpu_count()} cores: {len(records)} runs of {len(order)} experiments at the {args.profile} "
             + (f"profile ({copies} of them copies of a twin run with the same run function, parameters and seed, "
                "computed once), " if copies else "profile, ")
             + f"made at commit{'s' if len(commits) > 1 else ''} {', '.join(commits[:6])}"
             + (f" and {len(commits) - 6} more" if len(commits) > 6 else "") + "."]
    if wall is not None:
        use = pool_usage(records, args.workers, start, end)
        lines += ["", f"- `connrl reproduce --profile {args.profile}`: **{wall / 60:.1f} min** wall, "
                  f"{cpu / 60:.1f} min CPU in all processes; the runs themselves {total / 60:.1f} min "
                  f"({use['utilisation']:.0%} of {args.workers} cores' time).",
                  f"- Idle: {use['idle_s'] / 60:.1f} core-min in all; before the first run {use['head_s']:.0f} s; "
                  f"the pool's tail (fewer than {args.workers} runs left in flight) {use['tail_s']:.0f} s, "
                  f"{use['tail_idle_s']:.0f} core-s idle; the rest is the gaps between runs (starting, writing, "
                  "the page)."]
    lines += ["", "| chapter | experiment | runs | run time (min) | CPU (min) | share | longest run (s) | "
              "span in the pool (min) |", "|---|---|---|---|---|---|---|---|"]
    for name in sorted(order, key=lambda n: (chapter_of[n], -per.get(n, {}).get("run_s", 0))):
        e = per.get(name)
        if e is None:
            continue
        span = f"{(e['last'] - e['first']) / 60:.1f}" if wall is not None and e["runs"] else "–"
        cpu = f"{e['cpu_s'] / 60:.2f}" if e["cpu_known"] else "–"
        runs = f"{e['runs']} (+{e['copies']} copied)" if e["copies"] else str(e["runs"])
        lines.append(f"| {chapter_of[name]} | {name} | {runs} | {e['run_s'] / 60:.2f} | {cpu} | "
                     f"{e['run_s'] / total:.1%} | {e['longest_s']:.1f} | {span} |")
    lines += ["", "| chapter | runs | run time (min) | over the cores (min) |", "|---|---|---|---|"]
    for chapter in sorted(set(chapter_of[n] for n in order)):
        es = [per[n] for n in order if chapter_of[n] == chapter and n in per]
        s = sum(e["run_s"] for e in es)
        lines.append(f"| {chapter} | {sum(e['runs'] for e in es)} | {s / 60:.1f} | {s / 60 / args.workers:.1f} |")
    lines.append(f"| all | {len(records) - copies} | {total / 60:.1f} | {total / 60 / args.workers:.1f} |")
    return lines


def profile_top(records, specs, n, profile) -> list[str]:
    per = per_experiment(records)
    top = sorted(per, key=lambda k: -per[k]["run_s"])[:n]
    lines = ["", f"The {n} most expensive experiments, each one's longest run again under cProfile (own time of every "
             "function, by kind; cProfile slows Python calls more than compiled kernels, so the Python shares are "
             "upper bounds):", "",
             "| experiment | run | compiled trials | environment | action selection | learning | bookkeeping |",
             "|---|---|---|---|---|---|---|"]
    for name in top:
        rec = max((r for r in computed(records) if r["experiment"] == name), key=lambda r: r["wall_time_s"])
        shares = profile_run(specs[name], rec, profile)
        s = sum(shares.values()) or 1.0
        lines.append(f"| {name} | {rec['variant']}, seed {rec['seed']} | "
                     + " | ".join(f"{v / s:.0%}" for v in shares.values()) + " |")
    return lines


if __name__ == "__main__":
    main()
