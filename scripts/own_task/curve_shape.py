"""The shape of saved learning curves: does a run that reaches the threshold keep it, plateau below it, or fall away?

    python scripts/own_task/curve_shape.py FOLDER [--blocks 500000]

FOLDER holds the runs ``sample_efficiency.py --save`` wrote (one JSON file per run). Per run: the steps at its first
evaluation at the task's threshold, how many of its evaluations reach it, the quartiles of the evaluations from that
first one on (all of them for a run that never reached it), the mean greedy return per block of steps, and its
training wall-clock (evaluations left out).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from connrl.storage import read_json

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from bench_gymnasium import TASKS  # noqa: E402


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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path)
    ap.add_argument("--blocks", type=int, default=500_000, help="steps per block of the mean greedy return")
    args = ap.parse_args()
    if args.blocks < 1:
        ap.error(f"--blocks must be 1 step or more, got {args.blocks}")
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
    for doc in sorted(docs, key=lambda d: (d["task"], d.get("row", ""), d["seed"])):
        print(f"{doc['task']} {doc['kind']} {doc.get('row', '')}".rstrip() + f"  {shape_line(doc, args.blocks)}")


if __name__ == "__main__":
    main()
