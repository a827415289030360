"""How connrl.own.api's defaults were chosen: QCON-R on CartPole-v1 and Acrobot-v1 with each default varied one at a
time (the others kept), on development seeds (100-108; the README's held-out seeds are 0-2 and 200-204); prints
the greedy return (mean of 10 episodes, evaluation seeds 500-509) after ``--steps`` steps, per seed and averaged.

    python scripts/own_task/defaults_sweep.py [--seeds 100 101 102] [--steps 50000] [--workers 2] [--out FILE.json]
        [--tasks CartPole-v1 Acrobot-v1] [--variants defaults "lam 0.9" ...]
"""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ProcessPoolExecutor

import gymnasium as gym
import numpy as np

import connrl

VARIANTS = {"defaults": {}, "gamma 0.95": {"gamma": 0.95}, "gamma 0.995": {"gamma": 0.995},
            "t_start 0.02": {"t_start": 0.02}, "t_start 0.1": {"t_start": 0.1},
            "lessons_per_trial 10": {"lessons_per_trial": 10}, "lessons_per_trial 40": {"lessons_per_trial": 40},
            "lam 0.5": {"lam": 0.5}, "lam 0.9": {"lam": 0.9}, "hidden 32": {"hidden": 32}}
TASKS = ("CartPole-v1", "Acrobot-v1")


def one(job: tuple[str, str, int, int]) -> tuple[str, str, int, float]:
    task, variant, seed, steps = job
    env = gym.make(task)
    agent = connrl.make_agent(env, "QCON-R", seed=seed, **VARIANTS[variant]).learn(steps)
    return task, variant, seed, float(np.mean(connrl.evaluate(agent, env, 10, seed=500)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[100, 101, 102])
    ap.add_argument("--steps", type=int, default=50_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None, help="also write the per-seed returns as JSON")
    ap.add_argument("--tasks", nargs="+", default=list(TASKS), choices=TASKS)
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    args = ap.parse_args()
    jobs = [(t, v, s, args.steps) for t in args.tasks for v in args.variants for s in args.seeds]
    results = []
    with ProcessPoolExecutor(args.workers) as pool:
        for r in pool.map(one, jobs):  # in order, each printed as it is known
            results.append(r)
            print(f"{r[0]} {r[1]} seed {r[2]}: {r[3]:.1f}", flush=True)
    table = {}
    for task, variant, seed, mean in results:
        table.setdefault(task, {}).setdefault(variant, {})[seed] = mean
    for task, rows in table.items():
        print(f"\n{task}, QCON-R, {args.steps} steps, greedy return per seed {args.seeds} and mean")
        for variant, per_seed in rows.items():
            values = [per_seed[s] for s in args.seeds]
            print(f"  {variant:<22} {' '.join(f'{v:8.1f}' for v in values)}   mean {np.mean(values):8.1f}")
    if args.out:
        with open(args.out, "w") as f:
            json.dump({"steps": args.steps, "seeds": args.seeds, "returns": table}, f, indent=1)


if __name__ == "__main__":
    main()
