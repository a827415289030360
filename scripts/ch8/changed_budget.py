"""How much of the changed layout's room-B shortfall is the 200-step limit? (issue 28; ours)

Trains Ch. 8's Exp. 2 (recurrent-Q, no X-Y, as ``connrl run integration`` runs it) on each development seed, then,
learning off, plays the final greedy policy in the changed layout (8.4) on ``--tasks`` fresh tasks per start room
with the test's step limit at 200 (the thesis's), 300 and 400, and prints the share docked from A / B / C per limit
(mean over seeds) and room B's per seed. About 5 minutes on 2 cores at 6 seeds.

    python scripts/ch8/changed_budget.py [--seeds 100:106] [--tasks 20]
"""

from __future__ import annotations

import argparse
import dataclasses
from multiprocessing import Pool

import numpy as np

from connrl.envs.robot.recharge import ROOMS, sample_in_room
from connrl.experiments.integration import EXPERIMENTS, greedy_trial
from connrl.experiments.recharge import run_rooms
from connrl.experiments.sweep import parse_seeds
from connrl.report.integration import RECURRENT
from connrl.tasks.integration import make_integration_agent, make_integration_env

LIMITS = (200, 300, 400)


def _one(job) -> list[list[float]]:
    seed, n_tasks = job
    spec = EXPERIMENTS[0]
    p = spec.variant_params(spec.params, next(v for v in spec.variants if v.label == RECURRENT))
    _, agent = run_rooms(p, np.random.default_rng(seed), make_integration_env, make_integration_agent)
    out = []
    for limit in LIMITS:
        env = make_integration_env(dataclasses.replace(p, max_steps=limit), "changed")
        task_rng = np.random.default_rng([seed, 8])  # the same tasks at every limit
        out.append([np.mean([greedy_trial(env, agent, sample_in_room(task_rng, env.world.layout, room),
                                          int(task_rng.integers(2**31)))[0] for _ in range(n_tasks)])
                    for room in ROOMS])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="100:106")
    ap.add_argument("--tasks", type=int, default=20, help="fresh changed-layout tasks per start room")
    args = ap.parse_args()
    try:
        a, b = parse_seeds(args.seeds)
        if args.tasks < 1:
            raise ValueError(f"--tasks must be >= 1, got {args.tasks}")
    except ValueError as exc:
        raise SystemExit(f"changed_budget: {exc}") from None
    with Pool(2) as pool:
        res = np.array(pool.map(_one, [(s, args.tasks) for s in range(a, b)]))
    for i, limit in enumerate(LIMITS):
        shares = " / ".join(f"{v:.2f}" for v in res[:, i].mean(0))
        print(f"changed layout, test limit {limit}: docked A / B / C {shares}; B per seed "
              f"{res[:, i, 1].round(2).tolist()}")


if __name__ == "__main__":
    main()
