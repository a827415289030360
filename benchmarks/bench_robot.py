"""Time the HEROINE simulator and the robot task envs (steps per second, sensing included).

    python benchmarks/bench_robot.py [--steps 100000]

Prints steps/s for: the raw simulator (apply + sense), RobotTaskEnv.step for each task (random
actions, resets at episode ends), and the same through gymnasium.make (with its wrappers).
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import connrl.envs  # noqa: F401  (registers the ids)
from connrl.envs.robot import RobotSim, RobotTaskEnv


def bench_sim(steps: int) -> float:
    rng = np.random.default_rng(0)
    sim = RobotSim("default", rng)
    sim.place(300, 60, 90)
    actions = rng.integers(0, 6, size=steps)
    sim.apply(0)
    sim.sense()  # compile / warm up
    t = time.perf_counter()
    for a in actions:
        sim.apply(int(a))
        sim.sense()
    return steps / (time.perf_counter() - t)


def bench_env(env, steps: int) -> float:
    env.reset(seed=0)
    actions = np.random.default_rng(0).integers(0, 6, size=steps)
    t = time.perf_counter()
    for a in actions:
        _, _, term, trunc, _ = env.step(int(a))
        if term or trunc:
            env.reset()
    return steps / (time.perf_counter() - t)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100_000)
    args = ap.parse_args()
    print(f"simulator apply+sense: {bench_sim(args.steps):>10,.0f} steps/s")
    for task in ("DK", "DP", "WFL", "WFR"):
        raw = bench_env(RobotTaskEnv(task), args.steps)
        made = bench_env(gym.make(f"connrl/Robot-{task}-v0"), args.steps)
        print(f"{task:>3} env.step (incl. resets): {raw:>10,.0f} steps/s   "
              f"via gym.make: {made:>10,.0f} steps/s")


if __name__ == "__main__":
    main()
