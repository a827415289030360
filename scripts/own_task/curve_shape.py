"""The shape of saved learning curves: does a run that reaches the threshold keep it, plateau below it, or fall away?

    python scripts/own_task/curve_shape.py FOLDER [--blocks 500000] [--until STEPS]

FOLDER holds the runs ``sample_efficiency.py --save`` wrote (one JSON file per run). Per run: the steps at its first
evaluation at the task's threshold, how many of its evaluations reach it, the quartiles of the evaluations from that
first one on (all of them for a run that never reached it), the mean greedy return per block of steps, and its
training wall-clock (evaluations left out). With ``--until``, each run read over its first STEPS steps instead, as a
run with that budget would have gone (no schedule reads the budget): its held solve by the benchmark's rule, its
area (the mean of its evaluations) and its wall-clock to there at its mean rate, then each row's totals (the median
counting a run that never held as beyond the steps, as the benchmark does).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from connrl.storage import read_json

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from bench_gymnasium import TASKS, _Curve  # noqa: E402


def shape_line(doc: dict, block: int) -> str:
    """One run's line (see the module's docstring)."""
    steps, returns = (np.array([p[i] for p in doc["curve"]], dtype=float) for i in (0, 1))
    at = returns >= TASKS[doc["task"]][0]
    first = int(np.argmax(at)) if at.any() else None
    after = returns[first:] if first is not None else returns
    q25, q50, q75 = np.percentile(after, [25, 50, 75])
    means = [returns[(steps > a) & (steps <= a + block)] for a in range(0, int(steps.max()), block)]
    blocks = " ".join(f"{m.mean():.0f}" if m.size else "-" for m in means)
    reach = f"{int(steps[first]):>9,}" if first is not None else f"{'never':>9}"
    span = "from first on" if first is not None else "all"
    return (f"seed {doc['seed']:>4}  first at {reach}  {int(at.sum()):>3} of {len(returns)} at it  "
            f"{span}: median {q50:.0f} (quartiles {q25:.0f}, {q75:.0f})  wall {doc['wall']:.0f} s  "
            f"| block means: {blocks}")


def until_line(doc: dict, until: int) -> tuple[str, int | None, float]:
    """One run read over its first ``until`` steps: its line, its held solve (steps, or None) and its area."""
    curve = _Curve(TASKS[doc["task"]][0])
    for steps, mean in doc["curve"]:
        if steps <= until:
            curve.add(steps, lambda m=mean: [m])
    area = float(np.mean([m for _, m in curve.points]))
    held = f"{curve.held:>9,}" if curve.held is not None else f"{'never':>9}"
    wall = doc["wall"] * min(until, doc["steps"]) / doc["steps"]
    return f"seed {doc['seed']:>4}  held at {held}  area {area:.1f}  wall {wall:.0f} s", curve.held, area


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path)
    ap.add_argument("--blocks", type=int, default=500_000, help="steps per block of the mean greedy return")
    ap.add_argument("--until", type=int, help="read each run over its first STEPS steps: held solve and area")
    args = ap.parse_args()
    if args.blocks < 1 or (args.until is not None and args.until < 1):
        ap.error(f"--blocks and --until must be 1 step or more, got {args.blocks} and {args.until}")
    files = sorted(args.folder.glob("*.json")) if args.folder.is_dir() else []
    if not files:
        ap.error(f"{args.folder}: no saved runs (JSON files written by sample_efficiency.py --save)")
    docs = []
    for f in files:
        try:
            doc = read_json(f)
            if not isinstance(doc, dict) or doc.get("task") not in TASKS or not doc.get("curve") or not all(
                    k in doc for k in ("seed", "kind", "wall")):
                raise ValueError("not a saved run of sample_efficiency.py")
            docs.append(doc)
        except (OSError, ValueError) as exc:
            ap.error(f"{f}: cannot read it ({exc})")
    docs.sort(key=lambda d: (d["task"], d.get("row", ""), d["seed"]))
    if args.until is None:
        for doc in docs:
            print(f"{doc['task']} {doc['kind']} {doc.get('row', '')}".rstrip() + f"  {shape_line(doc, args.blocks)}")
        return
    first = min(doc["curve"][0][0] for doc in docs)
    if args.until < first:
        ap.error(f"--until {args.until:,} is before the runs' first evaluation ({first:,} steps)")
    rows = {}  # the totals per row of the folder (a --vary folder holds several)
    for doc in docs:
        rows.setdefault((doc["task"], doc["kind"], doc.get("row", "")), []).append(doc)
    for (task, kind, row), group in rows.items():
        read = [until_line(doc, args.until) for doc in group]
        for line, _, _ in read:
            print(f"{task} {kind} {row}".rstrip() + f" over {args.until:,} steps  {line}")
        held = [h for _, h, _ in read if h is not None]
        median = np.median([math.inf if h is None else h for _, h, _ in read])  # never held: beyond any budget
        shown = f"{int(median):,} steps" if math.isfinite(median) else f"> {args.until:,} steps"
        area = np.mean([a for _, _, a in read])
        print(f"{args.folder.name} {row}".rstrip() + f": held on {len(held)} of {len(read)} (median {shown}), "
              f"mean area {area:.1f}")


if __name__ == "__main__":
    main()
