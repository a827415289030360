"""Sum the wall times that the stored full-profile summaries record, per chapter and in all (README, "Experiments").

    python scripts/thesis_time.py [--out runs]

Each summary's time is that of the `connrl run` that wrote it (on 2 cores unless it says otherwise), so the sum is an
estimate of `connrl reproduce --profile full`, not a measurement of it.
"""

import argparse
import json
from pathlib import Path

from connrl.experiments.registry import CHAPTERS, by_chapter


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="runs")
    args = ap.parse_args()
    total = 0.0
    for chapter in sorted(set(CHAPTERS.values())):
        seconds, missing = 0.0, []
        for spec in by_chapter([chapter]):
            f = Path(args.out) / spec.name / "summary.json"
            s = json.loads(f.read_text()) if f.exists() else None
            if s is None or s["profile"] != "full":
                missing.append(spec.name)
                continue
            seconds += s["timing"]["wall_time_s"]
        total += seconds
        print(f"chapter {chapter}: {seconds / 60:.1f} min" + (f" (no full summary: {', '.join(missing)})" if missing
                                                                else ""))
    print(f"all: {total / 60:.1f} min")


if __name__ == "__main__":
    main()
