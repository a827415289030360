"""7.5.1's computation time: where a Task 1 run's time goes for recurrent-Q and recurrent-model (lambda 0.8, 500
trials, one run each on one core, seed 0), measured with cProfile: the whole run, per trial, and the cumulative time
in the parts the thesis names (model training; Q-net replay) and in the compiled net arithmetic inside them.

    python scripts/ch7/compute_time.py [--seed 0] [--repeat 3]

The thesis: recurrent-Q took 20 minutes a run and recurrent-model 80, "because the recurrent-model architecture had
to learn a model as well as a feed-forward Q-net and the model network was much bigger than the recurrent Q-net".
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

import numpy as np

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=3, help="unprofiled runs per architecture; the fastest counts")
    args = ap.parse_args()
    if args.seed < 0 or not 1 <= args.repeat <= 20:
        ap.error(f"--seed must be 0 or more and --repeat in [1, 20], got {args.seed} and {args.repeat}")
    walls, kernels = {}, {}
    for arch in ("recurrent-Q", "recurrent-model"):
        run_cup(CupParams(task=1, arch=arch, lam=0.8, probe=False, trials=3), np.random.default_rng(1))  # compile
        p = CupParams(task=1, arch=arch, lam=0.8, probe=False)
        wall = float("inf")
        for _ in range(args.repeat):  # the fastest of a few: this machine's neighbours add noise, never speed
            t0 = time.perf_counter()
            run_cup(p, np.random.default_rng(args.seed))
            wall = min(wall, time.perf_counter() - t0)
        prof = cProfile.Profile()
        prof.enable()
        run_cup(p, np.random.default_rng(args.seed))
        prof.disable()
        stats = pstats.Stats(prof)
        total = cumulative(stats, "experiments/hidden_state.py", "run_cup")
        print(f"{arch}: {wall:.2f} s a run ({1000 * wall / p.trials:.1f} ms a trial; fastest of {args.repeat}) "
              "without the profiler; "
              f"under it {total:.2f} s, of which:")
        for label, (suffix, name) in PARTS.items():
            t = cumulative(stats, suffix, name)
            if t:
                print(f"  {label:<60} {t:6.2f} s  {100 * t / total:5.1f} %")
        walls[arch] = wall
        kernels[arch] = sum(cumulative(stats, suffix, name) for label, (suffix, name) in PARTS.items()
                            if label.startswith("compiled"))  # what cProfile sees of them: called from Python
    print(f"recurrent-model / recurrent-Q: whole runs {walls['recurrent-model'] / walls['recurrent-Q']:.1f}x; "
          f"the compiled kernels alone {kernels['recurrent-model']:.2f} s / {kernels['recurrent-Q']:.2f} s = "
          f"{kernels['recurrent-model'] / kernels['recurrent-Q']:.1f}x")


if __name__ == "__main__":
    main()
