"""Which scale of mu gives the thesis's mean group size? (calibration of state grouping, Experiment 4, 6.6.4)

The thesis groups consecutive states whose inputs lie within mu ~ U(0.5, 2.5) and reports "in average, every 11
states were grouped together". Its input scale is not ours (the X-Y units and the sonar averaging are
reconstructions), so the same mu groups far more of our states. This collects exploration lessons of Experiment
4's world (a fresh learner with the persistence rule, steps shrunk to a fifth, 1000-step trials; seed 100, a
development seed) and prints the mean group size for mu ~ U(0.5 c, 2.5 c) over a range of scales c.

    python scripts/ch6/group_size.py [--trials 6] [--seed 100]
"""

from __future__ import annotations

import argparse

import numpy as np

from connrl.core.grouping import group_states
from connrl.core.rollout import run_trial
from connrl.experiments.recharge import RechargeParams
from connrl.tasks.recharge import make_high_level_agent, make_recharge_env


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=6)
    ap.add_argument("--seed", type=int, default=100)
    args = ap.parse_args()
    p = RechargeParams(step_scale=0.2, max_steps=1000, success_reward=500.0, gamma=0.998, lam=0.8)
    rng = np.random.default_rng(args.seed)
    env, agent = make_recharge_env(p), make_high_level_agent(p, rng)
    env.reset(seed=int(rng.integers(2**31)))
    lessons = []
    for k in range(args.trials):
        run_trial(env, agent, trial=k, learning=True)
        lessons.append(agent.book.memory.lessons[-1])
    steps = sum(len(lesson) for lesson in lessons)
    for c in (1.0, 0.7, 0.6, 0.5, 0.45, 0.4, 0.35, 0.3):
        g = sum(len(group_states(lesson.inputs[:-1], (0.5 * c, 2.5 * c), rng, lesson.actions)) for lesson in lessons)
        print(f"mu ~ U({0.5 * c:.3f}, {2.5 * c:.3f}): mean group size {steps / g:.1f} ({steps} steps)")


if __name__ == "__main__":
    main()
