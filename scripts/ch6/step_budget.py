"""How much of room B's shortfall at trial 60 is the 200-step limit? (a diagnosis for issue 27)

Trains Exp. 3 (``connrl.experiments.recharge.run_recharge``, the defaults) for ``--trials`` trials on each development
seed, then plays the final greedy policy on that run's own fixed test tasks with the test's step limit at 200 (the
thesis's), 300 and 400, and prints the share docked from A / B / C per limit (mean over seeds) and room B's per seed.
A policy that docks with 400 steps but not with 200 reaches the charger, slowly (dithering, long routes); one that
fails at 400 does not get there. About 50 s on 2 cores at 20 seeds.

    python scripts/ch6/step_budget.py [--seeds 100:120] [--trials 60]
"""

from __future__ import annotations

import argparse
import dataclasses
from multiprocessing import Pool

import numpy as np

import connrl.experiments.recharge as rx
from connrl.core.rollout import run_trial
from connrl.envs.robot.recharge import ROOMS, sample_in_room
from connrl.experiments.recharge import LAYOUT, RechargeParams, run_recharge

LIMITS = (200, 300, 400)


def _one(job) -> list[list[float]]:
    seed, trials = job
    p, made = RechargeParams(trials=trials), {}
    make_agent = rx.make_high_level_agent

    def keep(params, rng):
        made["agent"] = make_agent(params, rng)
        return made["agent"]

    rx.make_high_level_agent = keep  # this worker process only
    run_recharge(p, np.random.default_rng(seed))
    task_rng = np.random.default_rng(np.random.default_rng(seed).integers(2**63))  # the run's tasks, as run_rooms
    tasks = [(r, sample_in_room(task_rng, LAYOUT, r)) for r in ROOMS for _ in range(p.tests_per_room)]
    seeds = task_rng.integers(2**31, size=len(tasks))
    out = []
    for limit in LIMITS:
        env, docked = rx.make_recharge_env(dataclasses.replace(p, max_steps=limit)), dict.fromkeys(ROOMS, 0)
        for (room, start), s in zip(tasks, seeds, strict=True):
            stats = run_trial(env, made["agent"], trial=0, learning=False, seed=int(s), options={"start": start})
            docked[room] += bool(stats.info.get("success"))
        out.append([docked[r] / p.tests_per_room for r in ROOMS])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="100:120")
    ap.add_argument("--trials", type=int, default=60)
    args = ap.parse_args()
    a, b = map(int, args.seeds.split(":"))
    with Pool(2) as pool:
        res = np.array(pool.map(_one, [(s, args.trials) for s in range(a, b)]))
    for i, limit in enumerate(LIMITS):
        print(f"test limit {limit}: docked A / B / C {' / '.join(f'{v:.2f}' for v in res[:, i].mean(0))}; "
              f"B per seed {res[:, i, 1].round(1).tolist()}")


if __name__ == "__main__":
    main()
