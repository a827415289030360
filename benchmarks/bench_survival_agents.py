"""Time per training play of each Ch. 4 framework (and per test play), to budget the survival studies.

    python benchmarks/bench_survival_agents.py [--plays 20] [--representation global|local|both]

Prints, per agent configuration: ms per training play (acting + on-line learning + replay/planning),
steps per play, and ms per greedy test play; then projects Study 1 + Study 2 (protocol of 4.3.1: 300
plays + 16 tests of 50 plays per run, 7 runs) on the given number of cores. Early plays are short (the
agent dies quickly), so this measures plays 0..N of a fresh agent with the per-play replay amount of
play 150 (8 lessons) to approximate the average cost over a run.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from connrl.core.rollout import run_trial
from connrl.envs.survival import SurvivalEnv
from connrl.tasks.survival import SurvivalAgentParams, make_survival_agent

CONFIGS = [("AHCON", "learned"), ("AHCON-R", "learned"), ("AHCON-M", "learned"), ("AHCON-M", "perfect"),
           ("AHCON-T", "learned"), ("QCON", "learned"), ("QCON-R", "learned"), ("QCON-M", "learned"),
           ("QCON-M", "perfect"), ("QCON-T", "learned")]


def bench(framework: str, model: str, representation: str, plays: int, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed)
    env = SurvivalEnv(representation)
    env.reset(seed=seed)
    agent = make_survival_agent(SurvivalAgentParams(framework, representation, model,
                                                    lr_scale=1.0 if representation == "global" else 2.0), env, rng)
    run_trial(env, agent, trial=0, learning=True)  # warm up (Numba compile/cache load)
    steps, t0 = 0, time.perf_counter()
    for k in range(plays):
        steps += run_trial(env, agent, trial=150 if k else 11, learning=True).steps
    train = (time.perf_counter() - t0) / plays
    tsteps, t0 = 0, time.perf_counter()
    for _ in range(plays):
        tsteps += run_trial(env, agent, trial=0, learning=False).steps
    test = (time.perf_counter() - t0) / plays
    return {"train_ms": 1e3 * train, "steps": steps / plays, "test_ms": 1e3 * test, "test_steps": tsteps / plays}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--plays", type=int, default=20)
    ap.add_argument("--representation", default="both", choices=("global", "local", "both"))
    ap.add_argument("--cores", type=int, default=2)
    args = ap.parse_args()
    reps = ("global", "local") if args.representation == "both" else (args.representation,)
    total = 0.0
    print(f"{'agent':<22}{'rep':<8}{'ms/play':>9}{'steps':>7}{'us/step':>9}{'test ms':>9}{'run s':>8}")
    for rep in reps:
        for fw, model in CONFIGS:
            r = bench(fw, model, rep, args.plays)
            label = fw + (f" ({model})" if fw.endswith("-M") else "")
            run_s = (300 * r["train_ms"] + 16 * 50 * r["test_ms"]) / 1e3  # one run of the 4.3.1 protocol
            total += 7 * run_s
            print(f"{label:<22}{rep:<8}{r['train_ms']:9.1f}{r['steps']:7.0f}{1e3 * r['train_ms'] / r['steps']:9.1f}"
                  f"{r['test_ms']:9.1f}{run_s:8.1f}")
    print(f"projected: {total / 60:.1f} core-minutes for 7 runs of every configuration above; "
          f"{total / 60 / args.cores:.1f} min on {args.cores} cores")


if __name__ == "__main__":
    main()
