"""Time the survival env's hot path: step() including the 145-unit observation (target <= 30 us/step).

Run: python benchmarks/bench_survival_env.py [n_steps]
Random actions; plays are reset when they end (reset time included, it is ~1 per 60 steps).
"""

import sys
import time

import gymnasium as gym
import numpy as np

import connrl.envs  # noqa: F401  (registers connrl/Survival-v0)
from connrl.envs.survival import SurvivalEnv, rotate_observation


def bench(env, n_steps: int, seed: int = 0) -> float:
    rng = np.random.default_rng(seed)
    actions = rng.integers(4, size=n_steps)
    env.reset(seed=seed)
    for a in actions[:1000]:  # warm-up (numba compilation / cache load)
        if any(env.step(int(a))[2:4]):
            env.reset()
    t0 = time.perf_counter()
    for a in actions:
        _, _, terminated, truncated, _ = env.step(int(a))
        if terminated or truncated:
            env.reset()
    return n_steps / (time.perf_counter() - t0)


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 200_000
    for rep in ("global", "local"):
        sps = bench(SurvivalEnv(action_representation=rep), n)
        print(f"SurvivalEnv({rep!r:8}) raw        : {sps:10,.0f} steps/s  ({1e6 / sps:5.1f} us/step)")
    sps = bench(gym.make("connrl/Survival-v0"), n)
    print(f"gym.make('connrl/Survival-v0')       : {sps:10,.0f} steps/s  ({1e6 / sps:5.1f} us/step)")
    env = SurvivalEnv()
    obs, _ = env.reset(seed=0)
    t0 = time.perf_counter()
    for k in range(n):
        rotate_observation(obs, k & 3)
    print(f"rotate_observation                   : {1e6 * (time.perf_counter() - t0) / n:5.2f} us/call")
    m = n // 10
    t0 = time.perf_counter()
    for _ in range(m):
        env.set_state(env.get_state())
    print(f"get_state + set_state                : {1e6 * (time.perf_counter() - t0) / m:5.1f} us/call")


if __name__ == "__main__":
    main()
