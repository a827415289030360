"""Check of a cup-task variant over many seeds (the measurements quoted in
connrl/experiments/hidden_state.py and docs/RESULTS.md).

    python scripts/cup_variants.py '{"arch": "window-Q", "window_q_inv_t": [10, 30]}' 100 130
    python scripts/cup_variants.py '{"arch": "recurrent-Q", "task": 3, "lessons_per_trial": 20}' 100 108

The JSON overrides ``CUP_PARAMS`` (add "task": 2 or 3 for the other tasks); seeds run from the first number
to the second (exclusive), one run each, seeded as ``numpy.random.default_rng(seed)``. Prints, per run, the
first trial at 14 steps, the share of the last 100 tests at 14, their mean steps and the histogram of test
steps; then the number of runs stably optimal (>= 99 % of the last 100 tests at 14).
"""

import json
import sys
import time

import numpy as np

from connrl.experiments.hidden_state import CUP_PARAMS, run_cup


def main(argv: list[str]) -> None:
    if len(argv) != 3:
        raise SystemExit(__doc__)
    over, first, stop = json.loads(argv[0]), int(argv[1]), int(argv[2])
    unknown = set(over) - set(CUP_PARAMS)
    if unknown:
        raise SystemExit(f"unknown parameters {sorted(unknown)}; allowed: {sorted(CUP_PARAMS)}")
    t0, res = time.time(), []
    for seed in range(first, stop):
        r = run_cup({**CUP_PARAMS, "probe": False, **over}, np.random.default_rng(seed))
        ys = np.array(r.curve_y[-100:])
        hist = {int(k): int(v) for k, v in zip(*np.unique(ys, return_counts=True), strict=True)}
        res.append((seed, r.metrics["trials_to_optimal"], float(np.mean(ys == 14)), float(ys.mean()), hist))
        print(f"  seed {seed}: first at 14 {r.metrics['trials_to_optimal']}, share at 14 {res[-1][2]:.2f}, "
              f"mean steps {res[-1][3]:.2f}, steps histogram {hist}", flush=True)
    stable = sum(r[2] >= 0.99 for r in res)
    reached = sum(r[1] is not None for r in res)
    print(f"{json.dumps(over)}: stably optimal {stable}/{len(res)}, reached 14 {reached}/{len(res)}, "
          f"mean share at 14 {np.mean([r[2] for r in res]):.2f}, mean steps {np.mean([r[3] for r in res]):.2f} "
          f"({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main(sys.argv[1:])
