"""Check of a Ch. 5 robot variant over many seeds (the measurements quoted in connrl/experiments/robot.py).

    python scripts/robot_variants.py '{"task": "DK", "lessons": 10, "lr": 0.04, "hidden_fraction": 0.0,
        "momentum": 0.0, "binary_low": 0.0, "linear_output": true}' 100 107

The JSON overrides ``ROBOT_PARAMS``; seeds run from the first number to the second (exclusive), one run each,
seeded as ``numpy.random.default_rng(seed)``. Prints the mean final performance (last 3 tests), the mean
over the whole curve, and every 5th point of the mean curve (tests every 10 trials).
"""

import json
import sys
import time

import numpy as np

from connrl.experiments.robot import ROBOT_PARAMS, run_robot


def main(argv: list[str]) -> None:
    if len(argv) != 3:
        raise SystemExit(__doc__)
    over, first, stop = json.loads(argv[0]), int(argv[1]), int(argv[2])
    unknown = set(over) - set(ROBOT_PARAMS)
    if unknown:
        raise SystemExit(f"unknown parameters {sorted(unknown)}; allowed: {sorted(ROBOT_PARAMS)}")
    t0, finals, curves = time.time(), [], []
    for seed in range(first, stop):
        r = run_robot({**ROBOT_PARAMS, **over}, np.random.default_rng(seed))
        finals.append(r.metrics["final_performance"])
        curves.append(r.curve_y)
    c = np.mean(curves, axis=0)
    print(f"{json.dumps(over)}: final {np.mean(finals):.2f}, mean {c.mean():.2f}, "
          f"mean curve every 50 trials {np.round(c[::5], 1).tolist()} ({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main(sys.argv[1:])
