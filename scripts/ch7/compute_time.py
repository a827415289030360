"""7.5.1's computation time: a Task 1 run of recurrent-Q and of recurrent-model (lambda 0.8, 500 trials, seed 0, one
core). Unprofiled runs in alternating rounds give the median and range of a run's seconds and of the ratio, also
against recurrent-Q with its lessons replayed by the Python composition (as before issue 32 compiled it); one run
each under cProfile gives the cumulative time in the parts the thesis names (model training; Q-net replay) and in
the compiled net arithmetic inside them.

    python scripts/ch7/compute_time.py [--seed 0] [--repeat 5]

The thesis: recurrent-Q took 20 minutes a run and recurrent-model 80, "because the recurrent-model architecture had
to learn a model as well as a feed-forward Q-net and the model network was much bigger than the recurrent Q-net".
"""

from __future__ import annotations

import argparse
import cProfile
import functools
import pstats
import time

import numpy as np

import connrl.agents.memory as memory
from connrl.experiments.hidden_state import CupParams, run_cup

PARTS = {  # label -> (file suffix, function) whose cumulative time is reported
    "Q replay after each trial": ("agents/base.py", "learn"),
    "model training (BPTT) after each trial": ("agents/memory.py", "train_model"),
    "compiled recurrent-net forward kernel": ("nets/recurrent.py", "_forward_sequence"),
    "compiled recurrent-net BPTT kernel": ("nets/recurrent.py", "_bptt"),
    "compiled feed-forward replay kernel": ("nets/kernels.py", "_replay_q_kernel"),
    "compiled recurrent-Q lesson replay kernel": ("nets/recurrent.py", "_replay_q_lesson"),
    "greedy tests": ("experiments/hidden_state.py", "test"),
}


def cumulative(stats: pstats.Stats, suffix: str, name: str) -> float:
    return sum(v[3] for (file, _, func), v in stats.stats.items() if file.endswith(suffix) and func == name)


def timed_run(arch: str, seed: int, python_replay: bool = False) -> float:
    """Seconds of one unprofiled run; ``python_replay`` replays recurrent-Q's lessons by the Python composition
    (``fast=False``), as before issue 32 compiled it."""
    original = memory.replay_recurrent_q
    if python_replay:
        memory.replay_recurrent_q = functools.partial(original, fast=False)
    try:
        t0 = time.perf_counter()
        run_cup(CupParams(task=1, arch=arch, lam=0.8, probe=False), np.random.default_rng(seed))
        return time.perf_counter() - t0
    finally:
        memory.replay_recurrent_q = original


def profile(arch: str, seed: int) -> float:
    """One run under cProfile: prints where its time goes; returns the compiled kernels' time seen from Python."""
    prof = cProfile.Profile()
    prof.enable()
    run_cup(CupParams(task=1, arch=arch, lam=0.8, probe=False), np.random.default_rng(seed))
    prof.disable()
    stats = pstats.Stats(prof)
    total = cumulative(stats, "experiments/hidden_state.py", "run_cup")
    print(f"{arch} under cProfile: {total:.2f} s, of which:")
    for label, (suffix, name) in PARTS.items():
        t = cumulative(stats, suffix, name)
        if t:
            print(f"  {label:<60} {t:6.2f} s  {100 * t / total:5.1f} %")
    return sum(cumulative(stats, suffix, name) for label, (suffix, name) in PARTS.items()
               if label.startswith("compiled"))  # what cProfile sees of them: called from Python


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=5, help="rounds of unprofiled runs, the arms alternating")
    args = ap.parse_args()
    if args.seed < 0 or not 1 <= args.repeat <= 20:
        ap.error(f"--seed must be 0 or more and --repeat in [1, 20], got {args.seed} and {args.repeat}")
    arms = {"recurrent-Q": ("recurrent-Q", False), "recurrent-Q, Python lesson replay": ("recurrent-Q", True),
            "recurrent-model": ("recurrent-model", False)}
    for arch in ("recurrent-Q", "recurrent-model"):  # compile the kernels before any timing
        run_cup(CupParams(task=1, arch=arch, lam=0.8, probe=False, trials=3), np.random.default_rng(1))
    times = {arm: [] for arm in arms}
    for _ in range(args.repeat):  # alternating, so a slow spell of this shared machine hits every arm
        for arm, (arch, python_replay) in arms.items():
            times[arm].append(timed_run(arch, args.seed, python_replay))
    print(f"Unprofiled runs, {args.repeat} rounds: median (lowest-highest) seconds a run")
    for arm, t in times.items():
        print(f"  {arm:<40} {np.median(t):6.2f} ({min(t):.2f}-{max(t):.2f})")
    for base in ("recurrent-Q", "recurrent-Q, Python lesson replay"):
        r = np.array(times["recurrent-model"]) / np.array(times[base])  # per round
        print(f"recurrent-model / {base}: median {np.median(r):.1f}x ({r.min():.1f}-{r.max():.1f}x over the rounds)")
    kernels = {arch: profile(arch, args.seed) for arch in ("recurrent-Q", "recurrent-model")}
    print(f"the compiled kernels alone: {kernels['recurrent-model']:.2f} s / {kernels['recurrent-Q']:.2f} s = "
          f"{kernels['recurrent-model'] / kernels['recurrent-Q']:.1f}x")


if __name__ == "__main__":
    main()
