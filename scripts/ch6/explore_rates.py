"""How often does exploration alone reach the charger from each room? (a diagnosis of Ch. 6's Exps 2 and 3)

A fresh high-level learner (Experiment 2's or 3's W) chooses behaviours by Eq. 6.6 at the starting temperature 0.05,
without learning, for N trials of 200 primitive steps from each room; printed: the share of trials that dock. A room
that exploration never connects from gives the learner no reward to learn from; also printed, the share of trials from
B that reach C and from C that reach A on the way. Seeded; about a minute.

    python scripts/ch6/explore_rates.py [--trials 30] [--seed 100]
"""

from __future__ import annotations

import argparse

import numpy as np

from connrl.envs.robot.recharge import ROOMS
from connrl.experiments.recharge import RechargeParams
from connrl.tasks.recharge import make_high_level_agent, make_recharge_env


def rates(persistence: bool, room: str, trials: int, seed: int) -> tuple[float, float]:
    """(share of trials that dock, share that reach the room on the way: C from B, A from C, A itself)."""
    p = RechargeParams(persistence=persistence)
    rng = np.random.default_rng(seed)
    env, agent = make_recharge_env(p), make_high_level_agent(p, rng)
    docked = onward = 0
    target = {"B": "C", "C": "A", "A": "A"}[room]
    for _ in range(trials):
        obs, info = env.reset(seed=int(rng.integers(2**31)), options={"room": room})
        agent.begin_trial(obs, info, trial=0, learning=True)  # trial 0: T = 0.05; observe() is never called
        reached = info["room"] == target
        for _ in range(p.max_steps):
            agent._x = agent.encode(obs)
            obs, r, term, trunc, info = env.step(agent.act(obs, info))
            reached = reached or info["room"] == target
            if term or trunc:
                break
        docked += bool(info["success"])
        onward += reached
    return docked / trials, onward / trials


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=30)
    ap.add_argument("--seed", type=int, default=100)
    args = ap.parse_args()
    for persistence in (False, True):
        got = {room: rates(persistence, room, args.trials, args.seed) for room in ROOMS}
        print(f"{'Exp. 3 (persistence)' if persistence else 'Exp. 2 (W = 0/1)'}: docked within 200 steps from A / B / "
              f"C {' / '.join(f'{got[r][0]:.2f}' for r in ROOMS)}; reached C from B {got['B'][1]:.2f}, A from C "
              f"{got['C'][1]:.2f}")


if __name__ == "__main__":
    main()
