"""What the recurrent robot's memory adds, over two independent seed sets (issue 28; ours).

Compares Ch. 8's Exp. 2 (recurrent-Q, no X-Y) with the two learners that have its replays but no memory -- the same
nets without context units and the memoryless learner at 1000 lessons per trial -- on room B docked (last 3 tests)
and final performance: one-sided Welch per seed set and over both pooled. The page's runs (seeds 0-6) are read from
``--runs``; the fresh set is ``connrl sweep integration --variant LABEL --seeds A:B`` for each learner, run here (or
reused) into ``--out``:

    python scripts/ch8/memory_gain.py [--runs runs] [--seeds 200:207] [--out runs]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from connrl import cli
from connrl.experiments.integration import EXPERIMENTS
from connrl.experiments.sweep import parse_seeds, sweep_spec
from connrl.report.integration import NO_CONTEXT, RECURRENT, SAME_REPLAYS
from connrl.report.verdicts import better

QUANTITIES = ("final_docked_B", "final_performance")


def per_run(summary: dict, label: str, name: str) -> list[float]:
    return summary["variants"][label]["quantities"][name]["per_run"]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", default="runs", help="where `connrl run integration --profile full` stored its runs")
    ap.add_argument("--seeds", default="200:207", help="the fresh seed set, A:B")
    ap.add_argument("--out", default="runs", help="where the fresh sweeps are stored (reused when present)")
    args = ap.parse_args()
    page_file = Path(args.runs) / "integration" / "summary.json"
    try:
        parse_seeds(args.seeds)
        page = json.loads(page_file.read_text())
        missing = [x for x in (RECURRENT, SAME_REPLAYS, NO_CONTEXT) if x not in page.get("variants", {})]
        if missing:
            raise ValueError(f"{page_file} lacks the variant(s) {missing}: run `connrl run integration --profile full`")
    except (OSError, ValueError) as exc:
        raise SystemExit(f"memory_gain: {exc}") from None
    fresh = {}
    for label in (RECURRENT, SAME_REPLAYS, NO_CONTEXT):
        cli.main(["sweep", "integration", "--variant", label, "--seeds", args.seeds, "--out", args.out, "--quiet"])
        name = sweep_spec(EXPERIMENTS[0], [], label).name
        fresh[label] = json.loads((Path(args.out) / name / "summary.json").read_text())["variants"]["sweep"]
    print(f"\nrecurrent-Q against | quantity | seeds 0-6 | seeds {args.seeds} | pooled (one-sided Welch)")
    for label in (NO_CONTEXT, SAME_REPLAYS):
        for q in QUANTITIES:
            sets = [(per_run(page, RECURRENT, q), per_run(page, label, q)),
                    (fresh[RECURRENT]["quantities"][q]["per_run"], fresh[label]["quantities"][q]["per_run"])]
            sets.append((sets[0][0] + sets[1][0], sets[0][1] + sets[1][1]))
            cells = []
            for rec, other in sets:
                verdict, p = better(other, rec, higher_is_better=True)
                cells.append(f"{sum(rec) / len(rec):.2f} vs {sum(other) / len(other):.2f}, {verdict} (p = {p:.2g})")
            print(f"{label} | {q} | " + " | ".join(cells))


if __name__ == "__main__":
    main()
