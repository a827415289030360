"""How a behaviour's share of far-from-goal training starts sets where it is applicable (6.4.3).

Trains one behaviour of the library plan with the given share (the library's seed for it: DK 0, DP 1), draws its
Q-value map and prints its final test, its rate where Ch. 6 uses it, and the share of places near / away from its goal
where it counts as applicable (near: within 96 in of the light for DK; within 72 in of the door wall and 36 in of a
door centre for DP). About 15 s.

    python scripts/ch6/far_share.py DK 0.25
"""

from __future__ import annotations

import argparse

import numpy as np

from connrl.envs.robot import Layout
from connrl.experiments.behaviours import TrainingPlan, serve_rate, train_behaviour
from connrl.tasks.behaviours import APPLICABLE_ABOVE, q_value_map


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("task", choices=("DK", "DP"))
    ap.add_argument("far_share", type=float)
    args = ap.parse_args()
    layout = Layout.load("default")
    b = train_behaviour(TrainingPlan(args.task, far_share=args.far_share), {"DK": 0, "DP": 1}[args.task])
    xs, ys, grid = q_value_map(b, layout)
    if args.task == "DK":
        near = np.hypot(*np.meshgrid(xs - 9, ys - 9)) <= 96
    else:
        by_door = (np.abs(xs[None, :] - 114) <= 36) | (np.abs(xs[None, :] - 246) <= 36)
        near = (np.abs(ys[:, None] - 300) <= 72) & by_door
    free, applicable = ~np.isnan(grid), grid > APPLICABLE_ABOVE[args.task]
    print(f"{args.task} far_share {args.far_share:g}: final test {b.meta['final_test_performance']:.2f}, "
          f"rate where used {serve_rate(b, 0):.3f}, applicable near {applicable[free & near].mean():.2f}, "
          f"away {applicable[free & ~near].mean():.2f}")


if __name__ == "__main__":
    main()
