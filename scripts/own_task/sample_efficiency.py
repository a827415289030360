"""Sample efficiency of connrl's learners under bench_gymnasium.py's protocol, one setting varied at a time.

    python scripts/own_task/sample_efficiency.py --task CartPole-v1 [--seeds 100 101 102 103 104]
        [--base lr=0.05 ...] [--vary lr=0.02,0.1 lessons_per_trial=50] [--kind QCON-R | QCON-T ...]
        [--budget STEPS] [--taught EPISODES] [--no-base] [--save DIR] [--workers 1]

Each row: the base settings (the shipped settings file's entry for the task, then ``--base``) with one option changed.
Per row and seed the held-solve steps and the greedy return at the budget, with the median steps to a held solve (a run
that never held counts as more than the budget), the mean greedy return over all evaluations (the area under the
learning curve, which separates settings before either holds), at the budget, and the relapse ("lost": the share of
evaluations after a run first reaches the threshold that fall below it, over the runs that reached it). The defaults and
per-task settings of docs/PERFORMANCE.md were chosen with it on development seeds (100-104, 110-114), never on the
benchmark's seeds (0-4) or the fresh ones (200+).
"""

from __future__ import annotations

import argparse
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from connrl.own.api import KINDS, options_from
from connrl.storage import atomic_write_text, check_writable_dir, strict_json

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from bench_gymnasium import TASKS, TAUGHT_EPISODES, connrl_options, run_connrl  # noqa: E402
from gymnasium_report import Run, relapses  # noqa: E402


def _value(text: str):
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return {"none": None, "true": True, "false": False}.get(text.lower(), text)


def _pairs(items: list[str], what: str) -> dict:
    out = {}
    for item in items:
        if "=" not in item:
            raise SystemExit(f"{what} {item!r}: give option=value (for example lr=0.05)")
        k, v = item.split("=", 1)
        out[k] = v
    return out


def _job(args):
    task, seed, options, kind, budget, taught = args
    return run_connrl(task, seed, options, kind, budget=budget, taught=taught)


def lost_share(curve: list, threshold: float) -> float | None:
    """Relapse: the share of the evaluations after a run's first one at the threshold that fall below it (None for
    a run that never reached it, or reached it only at its last evaluation)."""
    below, later = relapses([Run("", "", 0, {"curve": curve})], threshold)  # the benchmark table's count
    return below / later if later else None


def summary_line(name: str, rs: list[dict], threshold: float) -> str:
    """One row of the table: held count, median held steps, area under the curve, greedy return at the budget, the
    mean relapse (``lost_share``) over the runs that reached the threshold, and per seed (held at / greedy at budget,
    ``!`` for a diverged run)."""
    held = [r["held"] if r["held"] is not None else math.inf for r in rs]
    med = float(np.median(held))
    area = np.mean([np.mean([p[1] for p in r["curve"]]) for r in rs])
    last = np.mean([r["curve"][-1][1] for r in rs])
    lost = [x for x in (lost_share(r["curve"], threshold) for r in rs) if x is not None]
    per = "  ".join(f"{r['held'] or '-'}/{r['curve'][-1][1]:.0f}{'!' if r['diverged'] else ''}" for r in rs)
    return (f"{name:<28} {sum(math.isfinite(h) for h in held):>2}/{len(rs):<2} "
            f"{f'{med:,.0f}' if math.isfinite(med) else '> budget':>12} {area:>8.1f} {last:>10.1f} "
            f"{f'{np.mean(lost):.2f} ({len(lost)})' if lost else '-':>9}   {per}")


def _save(args: argparse.Namespace, row: str, seed: int, options: dict, result: dict) -> None:
    """One run's evaluations as JSON in ``args.save``, named by task, learner, budget, row and seed."""
    taught = f"_t{args.taught}" if args.taught else ""
    doc = {"task": args.task, "seed": seed, "kind": args.kind, "taught": args.taught, "row": row, "options": options,
           "workers": args.workers, **result}
    atomic_write_text(args.save / f"{args.task}_{args.kind}{taught}_{args.budget}_{row}_{seed}.json", strict_json(doc))


def _args() -> argparse.Namespace:
    """The command line, checked before anything runs."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", required=True, choices=list(TASKS))
    ap.add_argument("--seeds", nargs="+", type=int, default=[100, 101, 102, 103, 104])
    ap.add_argument("--base", nargs="*", default=[], help="option=value on top of the shipped settings")
    ap.add_argument("--vary", nargs="*", default=[], help="option=v1,v2,...: one row per value")
    ap.add_argument("--kind", default="QCON-R", choices=[k for k in KINDS if k != "AHCON-T"])
    ap.add_argument("--taught", type=int, help=f"QCON-T: episodes of bench_gymnasium.py's teacher for the task "
                    f"(default {TAUGHT_EPISODES} on every task, so earlier rows rerun as printed; the benchmark's own "
                    "count per task is bench_gymnasium.taught_episodes: give it here to match)")
    ap.add_argument("--budget", type=int, help="environment steps per run (default: RL Zoo's DQN budget for the task)")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--save", type=Path, help="folder for each run's evaluations, one JSON file per run as it ends "
                    "(curve, held, times, options)")
    ap.add_argument("--no-base", action="store_true", help="only the --vary rows (the base row was run before: a run is"
                    " the same on every rerun)")
    args = ap.parse_args()
    if args.workers < 1:
        ap.error(f"--workers must be 1 or more, got {args.workers}")
    if args.budget is not None and not 10_000 <= args.budget <= 10_000_000:
        ap.error(f"--budget must be from 10,000 to 10,000,000 steps, got {args.budget:,}")
    if args.taught is not None and args.kind != "QCON-T":
        ap.error(f"--taught is for --kind QCON-T (the one taught learner this script runs), got --kind {args.kind}")
    if args.taught is not None and not 1 <= args.taught <= 100:
        ap.error(f"--taught must be from 1 to 100 episodes, got {args.taught}")
    if args.no_base and not args.vary:
        ap.error("--no-base leaves no row: give --vary")
    if len(args.vary) > len({item.split("=", 1)[0] for item in args.vary}):
        ap.error("--vary names an option twice: give its values in one list (lr=0.02,0.1)")
    if args.save is not None:
        try:
            check_writable_dir(args.save)
        except OSError as exc:
            ap.error(f"--save {args.save}: cannot write there ({exc})")
    args.budget = args.budget or TASKS[args.task][1]
    args.taught = args.taught or (TAUGHT_EPISODES if args.kind == "QCON-T" else None)
    return args


def main() -> None:
    args = _args()
    base = {**connrl_options(args.task), **{k: _value(v) for k, v in _pairs(args.base, "--base").items()}}
    rows = [] if args.no_base else [("base", base)]
    for k, values in _pairs(args.vary, "--vary").items():
        rows += [(f"{k}={v}", {**base, k: _value(v)}) for v in values.split(",")]
    for name, options in rows:  # every setting checked before anything runs
        try:
            options_from(options)
        except (ValueError, TypeError) as exc:
            raise SystemExit(f"sample_efficiency.py: error: {name}: {exc}") from None
    jobs = [(row, seed, options) for row, options in rows for seed in args.seeds]
    taught = args.taught or TAUGHT_EPISODES  # run_connrl's; QCON-R ignores it
    work = [(args.task, seed, options, args.kind, args.budget, taught) for _, seed, options in jobs]
    results = []
    with ProcessPoolExecutor(args.workers) as pool:  # in order; each run saved as soon as it and those before end
        try:
            for (row, seed, options), result in zip(jobs, pool.map(_job, work), strict=True):
                results.append(result)
                if args.save is not None:
                    _save(args, row, seed, options, result)
        except ValueError as exc:  # a budget the teacher's episodes use up: one line, not a worker's traceback
            raise SystemExit(f"sample_efficiency.py: error: {exc}") from None
    taught = f" taught {args.taught} episodes," if args.taught not in (None, TAUGHT_EPISODES) else ""
    print(f"{args.task}, {args.kind},{taught} {args.budget:,} steps, seeds {' '.join(map(str, args.seeds))}; base "
          f"{base or 'the defaults'}")
    print(f"{'setting':<28} {'held':>5} {'median held':>12} {'area':>8} {'at budget':>10} {'lost':>9}   per seed: "
          "held at / greedy at budget")
    n = len(args.seeds)
    for i, (name, _) in enumerate(rows):
        print(summary_line(name, results[i * n:(i + 1) * n], TASKS[args.task][0]), flush=True)


if __name__ == "__main__":
    main()
