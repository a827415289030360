"""Time QCON-T on the robot tasks of Ch. 5: the lesson-replay kernel, and whole trials of the protocol.

    python benchmarks/bench_robot_agent.py [--trials 60] [--task DP]

Prints: one 30-step lesson replayed by the Numba kernel vs the plain loop ``replay_q_reference`` (52-16-1 OAON x 6),
and the wall time per trial of ``run_robot`` (training trial + 60 replayed lessons + taught lessons + the
amortised test of 50 tasks every 10 trials), from which the time of the full Ch. 5 protocol follows.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from connrl.core.lessons import Lesson
from connrl.core.replay import ReplayParams, replay_q_reference
from connrl.core.replay_kernel import replay_oaon
from connrl.experiments.robot import EXPERIMENTS, RobotParams, run_robot
from connrl.nets import OAON, NetConfig


def bench_replay(reps: int = 300) -> tuple[float, float]:
    rng = np.random.default_rng(0)
    lesson = Lesson(rng.uniform(-0.5, 1, (31, 52)), rng.integers(0, 6, 30), rng.choice([0.0, -10.0], 30),
                    terminated=False, truncated=True)
    params = ReplayParams(gamma=0.9, lam=0.7, temperature=5.0, p_threshold=0.02)
    net = OAON(NetConfig(52, 16, 100.0, 0.5, 0.05, 0.9), 6, rng)
    replay_oaon(net, lesson, params)  # compile
    t = time.perf_counter()
    for _ in range(reps):
        replay_oaon(net, lesson, params)
    fast = (time.perf_counter() - t) / reps
    t = time.perf_counter()
    for _ in range(reps // 10):
        replay_q_reference(net, lesson, params)
    ref = (time.perf_counter() - t) / (reps // 10)
    return fast, ref


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=60)
    ap.add_argument("--task", default="DP", choices=("DP", "DK", "WFL"))
    args = ap.parse_args()
    fast, ref = bench_replay()
    print(f"replay of a 30-step lesson: kernel {fast * 1e6:8.0f} us   reference loop {ref * 1e6:8.0f} us")
    run_robot(RobotParams(trials=2, test_tasks=2), np.random.default_rng(0))  # compile
    p = RobotParams(task=args.task, lessons=10 if args.task != "WFL" else 5, trials=args.trials)
    t = time.perf_counter()
    run_robot(p, np.random.default_rng(0))
    per_trial = (time.perf_counter() - t) / args.trials
    n_runs = sum(len(s.variants) * s.resolve("full")[1] for s in EXPERIMENTS)
    print(f"{args.task}: {per_trial * 1e3:.1f} ms per trial over {args.trials} trials (tests included)")
    print(f"full Ch. 5 protocol: {n_runs} runs x 300 trials ~ {n_runs * 300 * per_trial / 60:.0f} core-minutes "
          "at this rate (the replay memory fills over the first 60 trials, so early trials are cheaper)")


if __name__ == "__main__":
    main()
