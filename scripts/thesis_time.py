"""Sum the wall times that the stored full-profile summaries record, per chapter and in all (docs/PERFORMANCE.md's
tables before issue 45 used it). Since issue 45, `connrl reproduce` runs all experiments as one pool and a summary
records its experiment's span in that pool, which overlaps the others': time a reproduce with
`python benchmarks/thesis_time.py` instead.

    python scripts/thesis_time.py [--out runs] [--chapters 6] [--per-experiment]

Each summary's time is that of the `connrl run` that wrote it (on 2 cores unless it says otherwise), so the sum is an
estimate of `connrl reproduce --profile full`, not a measurement of it. A `connrl run` that reused stored runs records
the reuse's wall time, not the runs'; where that is shorter than the longest stored run (impossible for a run that
computed them), the runs' own wall times over 2 workers stand in, and the line says so.
"""

import argparse
import json
from pathlib import Path

from connrl.experiments.registry import CHAPTERS, by_chapter
from connrl.report.wall import run_seconds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="runs")
    ap.add_argument("--chapters", default=None, help="comma-separated chapters (default: all)")
    ap.add_argument("--per-experiment", action="store_true", help="each experiment's wall time and commit too")
    args = ap.parse_args()
    total = 0.0
    chapters = sorted(set(CHAPTERS.values()))
    if args.chapters:
        asked = args.chapters.split(",")
        if not set(asked) <= {str(c) for c in chapters}:
            raise SystemExit(f"thesis_time: --chapters takes a comma-separated list of {chapters}, "
                             f"got {args.chapters!r}")
        chapters = [c for c in chapters if str(c) in asked]
    for chapter in chapters:
        seconds, missing, reused = 0.0, [], []
        for spec in by_chapter([chapter]):
            f = Path(args.out) / spec.name / "summary.json"
            s = json.loads(f.read_text()) if f.exists() else None
            if s is None or s["profile"] != "full":
                missing.append(spec.name)
                continue
            wall, runs = s["timing"]["wall_time_s"], run_seconds(s) or [0.0]  # copies of twin runs took no time
            if wall < max(runs):  # a reuse: estimate from the runs' own times
                wall = sum(runs) / 2
                reused.append(spec.name)
            seconds += wall
            if args.per_experiment:
                print(f"  {spec.name}: {wall:.0f} s ({sum(runs):.0f} s of run time, commit "
                      f"{(s.get('environment', {}).get('git_commit') or '?')[:7]})")
        total += seconds
        print(f"chapter {chapter}: {seconds / 60:.1f} min"
              + (f" (no full summary: {', '.join(missing)})" if missing else "")
              + (f" (reused, estimated from the runs' times over 2 workers: {', '.join(reused)})" if reused else ""))
    print(f"all: {total / 60:.1f} min")


if __name__ == "__main__":
    main()
