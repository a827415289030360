"""Time Ch. 6's hot paths: the high-level inputs, a behaviour-level step, one Exp. 3 run, and 6.2's greedy mapping.

    python benchmarks/bench_recharge.py [--trials 60]

Prints: the high-level inputs (``high_level_inputs``: all 16 units, its 8 sonar units by a compiled kernel) against
the NumPy definition of those 8 units alone (``encode_sonar(global_sonar(...))``, what they cost before); steps/s of
``BehaviourEnv.step`` with ``BehaviourQCON.act`` (greedy, the test phase's loop); the wall time of one Exp. 3 run
(``run_recharge``, tests included); and greedy mapping (``learn_model``) on a 2-D grid against its plain-Python
reference (``greedy_mapping_reference``).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from connrl.core.model_learning import greedy_mapping_reference, learn_model
from connrl.envs.grid import GridWorld
from connrl.envs.robot import Layout, encode_sonar
from connrl.envs.robot.recharge import global_sonar, high_level_inputs
from connrl.envs.robot.sim import Reading
from connrl.experiments.recharge import RechargeParams, run_recharge
from connrl.tasks.recharge import make_high_level_agent, make_recharge_env


def per_call(f, n: int) -> float:
    f()
    t = time.perf_counter()
    for _ in range(n):
        f()
    return (time.perf_counter() - t) / n


def bench_inputs(n: int = 20_000) -> tuple[float, float]:
    rng = np.random.default_rng(0)
    sonar, layout, bits = rng.uniform(0, 127, 24), Layout.load("default"), np.zeros(24, np.uint8)
    rd = Reading(sonar, sonar, bits, bits, np.zeros(4, np.uint8), 33.0, "B")
    return (per_call(lambda: high_level_inputs(rd, 100.0, 100.0, layout), n),
            per_call(lambda: encode_sonar(global_sonar(sonar, 33.0)), n))


def bench_steps(steps: int = 20_000) -> float:
    p = RechargeParams()
    env, agent = make_recharge_env(p), make_high_level_agent(p, np.random.default_rng(0))
    obs, info = env.reset(seed=0)
    agent.begin_trial(obs, info, learning=False)
    t = time.perf_counter()
    for _ in range(steps):
        obs, _, term, trunc, info = env.step(agent.act(obs, info, greedy=True))
        if term or trunc:
            obs, info = env.reset()
            agent.begin_trial(obs, info, learning=False)
    return steps / (time.perf_counter() - t)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=60)
    args = ap.parse_args()
    kernel, numpy_def = bench_inputs()
    print(f"high-level inputs, all 16 units (compiled sonar part): {kernel * 1e6:5.1f} us   NumPy definition of the 8 "
          f"sonar units alone: {numpy_def * 1e6:5.1f} us   ratio {numpy_def / kernel:.1f}x")
    print(f"BehaviourEnv.step + BehaviourQCON.act (greedy): {bench_steps():,.0f} steps/s")
    run_recharge(RechargeParams(trials=1, tests_per_room=1), np.random.default_rng(0))  # compile / load kernels
    t = time.perf_counter()
    run_recharge(RechargeParams(trials=args.trials), np.random.default_rng(0))
    wall = time.perf_counter() - t
    print(f"one Exp. 3 run of {args.trials} trials (7 tests of 30 tasks included): {wall:.1f} s")
    g = GridWorld(15, 2)
    fast = per_call(lambda: learn_model(g.next_state, starts=np.array([0])), 20)
    ref = per_call(lambda: greedy_mapping_reference(g.next_state, 0), 3)
    print(f"greedy mapping on a 15 x 15 grid: kernel {fast * 1e3:6.2f} ms   plain-Python reference "
          f"{ref * 1e3:7.1f} ms   ratio {ref / fast:.0f}x")


if __name__ == "__main__":
    main()
