"""The benchmark's teachers on their own: each hand-written teacher of ``benchmarks/bench_gymnasium.py`` (QCON-T's
three recorded episodes come from it) run greedily on the benchmark's evaluation episodes (environment seeds
10,000-10,009), so a held solve by QCON-T can be set against what it was shown.

    python scripts/own_task/teacher_scores.py [--tasks MountainCar-v0 ...] [--episodes 10]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from bench_gymnasium import EVAL_SEED, TASKS, TEACHERS, policy_returns  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=list(TEACHERS), choices=list(TEACHERS))
    ap.add_argument("--episodes", type=int, default=10)
    args = ap.parse_args()
    if not 1 <= args.episodes <= 1000:
        ap.error(f"--episodes must be from 1 to 1,000, got {args.episodes}")
    print(f"{'task':<16} {'threshold':>9} {'teacher mean':>12} {'min':>8} {'max':>8}   teacher "
          f"(evaluation seeds {EVAL_SEED:,}-{EVAL_SEED + args.episodes - 1:,})")
    for task in args.tasks:
        try:
            returns = policy_returns(gym.make(task), TEACHERS[task][1], args.episodes)
        except gym.error.DependencyNotInstalled:
            print(f"{task:<16} not run (Box2D is not installed: pip install -e \".[bench]\")")
            continue
        print(f"{task:<16} {TASKS[task][0]:>9g} {np.mean(returns):>12.1f} {min(returns):>8.1f} {max(returns):>8.1f}"
              f"   {TEACHERS[task][0]}")


if __name__ == "__main__":
    main()
