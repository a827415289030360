"""Run a sample of stored runs again and compare every number they stored, bit for bit: a speed-up must not move
the thesis's numbers (issue 45).

    python benchmarks/same_numbers.py --out results/thesis --per-experiment 1 [--only NAME,...] [--workers 2]
    python benchmarks/same_numbers.py --out results/thesis --against /tmp/thesis-full   # two stored folders

For each experiment stored in --out (at the profile its summary names), the first run of each of its first
--per-experiment variants (in the spec's order) is run again into a scratch folder, and its metrics, curve and
extra results (the .json) and its rows (the .csv) are compared with the stored ones. Prints one line per run;
exits 1 if any number moved. With --against, nothing runs: every run stored in both folders (same experiment, run
folder, variant and seed) is compared, and one line sums them up, naming the runs that differ.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

from blocks import paste

from connrl.experiments.registry import all_experiments
from connrl.experiments.runner import execute, make_jobs
from connrl.experiments.store import load_summary

COMPARED = ("metrics", "curve_x", "curve_y", "extra", "diverged")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/thesis")
    ap.add_argument("--per-experiment", type=int, default=1, help="variants per experiment (default 1)")
    ap.add_argument("--only", default=None, help="comma-separated experiments (default: all stored)")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--against", type=Path, default=None, help="compare with the runs stored there; run nothing")
    ap.add_argument("--write", type=Path, default=None, help="paste the summary into this Markdown file's block")
    ap.add_argument("--block", default="same_numbers", help="the block's name (default same_numbers)")
    args = ap.parse_args()
    if args.against:
        code, text = compare_folders(Path(args.out), args.against)
        if args.write:
            paste(args.write, args.block, f"python benchmarks/same_numbers.py --out {args.out} --against "
                  f"{args.against}", text)
        return code
    specs = all_experiments()
    names = args.only.split(",") if args.only else sorted(specs)
    unknown = [n for n in names if n not in specs]
    if unknown:
        raise SystemExit(f"same_numbers: unknown experiment(s) {', '.join(unknown)}")
    scratch = Path(tempfile.mkdtemp(prefix="same-numbers-"))
    todo, stored = [], {}
    for name in names:
        p = Path(args.out) / name / "summary.json"
        if not p.exists():
            continue
        s = load_summary(p, name)
        spec = specs[name]
        mine = make_jobs(spec, s["profile"], s["runs_per_variant"], s["base_seed"], Path(args.out))
        theirs = make_jobs(spec, s["profile"], s["runs_per_variant"], s["base_seed"], scratch)
        labels = [v.label for v in spec.variants][: args.per_experiment]
        for a, b in zip(mine, theirs, strict=True):
            if a.variant in labels and a.seed == s["base_seed"]:
                stored[b.path] = a.path
                todo.append(b)
    moved = 0
    for job, rec in execute(todo, min(args.workers, max(len(todo), 1)), False, "same numbers"):
        old = json.loads(Path(stored[job.path]).with_suffix(".json").read_text())
        diff = differences(Path(stored[job.path]), Path(job.path))
        moved += bool(diff)
        print(f"{'MOVED' if diff else 'same '} {job.experiment}: {job.variant} seed {job.seed} "
              f"({rec['wall_time_s']:.1f} s now, {old['wall_time_s']:.1f} s stored)"
              + (f": {', '.join(diff)} differ" if diff else ""), flush=True)
    summary = f"{len(todo) - moved} of {len(todo)} runs gave the stored numbers bit for bit"
    print(summary)
    if args.write:
        only = f" --only {args.only}" if args.only else ""
        paste(args.write, args.block, f"python benchmarks/same_numbers.py --out {args.out} --per-experiment "
              f"{args.per_experiment}{only}", summary)
    shutil.rmtree(scratch, ignore_errors=True)
    return 1 if moved else 0


def differences(old: Path, new: Path) -> list[str]:
    """What differs between two stored runs (paths without suffix): the compared record fields, and the CSV rows."""
    a, b = (json.loads(p.with_suffix(".json").read_text()) for p in (old, new))
    diff = [k for k in COMPARED if json.dumps(a.get(k), sort_keys=True) != json.dumps(b.get(k), sort_keys=True)]
    if old.with_suffix(".csv").read_text() != new.with_suffix(".csv").read_text():
        diff.append("the CSV rows")
    return diff


def folder_differences(out: Path, against: Path) -> tuple[dict[str, list[str]], int, int, int]:
    """Two stored folders run by run: (what differs in each run that differs, the runs in both, only in ``out``,
    only in ``against``)."""
    mine = {p.relative_to(out).with_suffix("") for p in out.glob("*/runs/*/*/seed-*.json")}
    theirs = {p.relative_to(against).with_suffix("") for p in against.glob("*/runs/*/*/seed-*.json")}
    diffs = {str(r): differences(out / r, against / r) for r in sorted(mine & theirs)}
    return {r: d for r, d in diffs.items() if d}, len(mine & theirs), len(mine - theirs), len(theirs - mine)


def compare_folders(out: Path, against: Path) -> tuple[int, str]:
    moved, both, only_out, only_against = folder_differences(out, against)
    lines = [f"MOVED {r}: {', '.join(d)} differ" for r, d in moved.items()]
    lines.append(f"{both - len(moved)} of the {both} runs stored in both {out} and {against} have the same numbers "
                 f"bit for bit ({only_against} only in {against}, {only_out} only in {out})")
    print("\n".join(lines))
    return (1 if moved else 0), "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
