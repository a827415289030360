"""Teaching on a user's task (3.7 through connrl.own.api): QCON-R against QCON-T given three episodes of a hand-written
teacher (``TEACHERS``: CartPole's is the README's), and AHCON-R, each on the same seeds and step budget; prints the
greedy return (mean of 10 episodes, evaluation seeds 500-509) per seed, and with ``--every N`` along the way.

    python scripts/own_task/teaching.py [--task CartPole-v1|MountainCar-v0|Acrobot-v1] [--seeds 0 1 2]
        [--steps 10000] [--every N] [--agents QCON-R QCON-T AHCON-R]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import connrl

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from bench_gymnasium import TEACHERS as _BENCH_TEACHERS  # noqa: E402  (one table of teachers: QCON-T's there)

TEACHERS = {task: teacher for task, (_, teacher) in _BENCH_TEACHERS.items()}  # observation -> action


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--steps", type=int, default=10_000)
    ap.add_argument("--agents", nargs="+", default=["QCON-R", "QCON-T", "AHCON-R"])
    ap.add_argument("--task", choices=sorted(TEACHERS), default="CartPole-v1")
    ap.add_argument("--every", type=int, default=None, help="also evaluate after every N steps")
    args = ap.parse_args()
    if args.every is not None and not 0 < args.every <= args.steps:
        raise SystemExit(f"teaching: --every must be in 1..--steps, got {args.every}")
    env = gym.make(args.task)
    with tempfile.TemporaryDirectory() as tmp:
        lessons = Path(tmp) / "teacher.json"
        taught = connrl.record_lessons(env, TEACHERS[args.task], 3, lessons)  # episodes on seeds 0-2, as the README
        print(f"teacher: 3 lessons, returns {[float(x.rewards.sum()) for x in taught]}")
        for kind in args.agents:
            means = []
            for seed in args.seeds:
                t0 = time.perf_counter()
                extra = {"lessons": lessons} if kind.endswith("-T") else {}
                agent = connrl.make_agent(env, kind, seed=seed, **extra)
                curve = []
                while agent.steps_done < args.steps:
                    agent.learn(min(args.every or args.steps, args.steps - agent.steps_done))
                    curve.append(float(np.mean(connrl.evaluate(agent, env, 10, seed=500))))
                mean = curve[-1]
                means.append(mean)
                along = f" (every {args.every}: {' / '.join(f'{c:.0f}' for c in curve)})" if args.every else ""
                print(f"{kind:<8} seed {seed}: {args.steps} steps ({agent.trials_done} trials), greedy return "
                      f"{mean:.1f}{along} ({time.perf_counter() - t0:.0f} s)", flush=True)
            print(f"{kind:<8} mean over seeds {args.seeds}: {np.mean(means):.1f}")


if __name__ == "__main__":
    main()
