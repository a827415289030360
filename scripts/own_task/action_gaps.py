"""How far apart a trained agent's action values are, against its final Boltzmann temperature.

    python scripts/own_task/action_gaps.py --task LunarLander-v3 [--kind QCON-T] [--taught 3] [--budget STEPS]
        [--base option=value ...] [--seeds 100 101] [--workers 1]

Trains as ``sample_efficiency.py`` does (bench_gymnasium.py's protocol, development seeds), then plays the greedy
policy on the benchmark's evaluation episodes and, at every state it visits, takes the gap between the best and the
second-best action value (return units). Per run: the median gap and its quartiles, the share of states whose gap is
below the final temperature (Boltzmann then picks the second-best action at least e^-1 as often as the best), that
temperature, and the greedy return. A suspect for LunarLander-v3's plateau (docs/notes/solve-protocol.md, addendum
12): a temperature near the gaps keeps the behaviour policy close to random among near-equal actions.
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import gymnasium as gym
import numpy as np

from connrl.own.api import options_from

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from bench_gymnasium import EVAL_EPISODES, EVAL_SEED, TASKS, TAUGHT_EPISODES, connrl_options, run_connrl  # noqa: E402


def gaps_of(agent, env, episodes: int, seed: int) -> tuple[np.ndarray, list[float]]:
    """The best-minus-second action-value gap at each state of ``episodes`` greedy episodes, and their returns."""
    gaps, returns = [], []
    with agent.greedy_weights():
        for k in range(episodes):
            obs, _ = env.reset(seed=seed + k)
            total, done = 0.0, False
            while not done:
                q = np.sort(agent.learner.q.values(agent.scaler.encode(obs)))
                gaps.append(q[-1] - q[-2])
                obs, r, terminated, truncated, _ = env.step(int(agent.predict(obs)[0]))
                total, done = total + float(r), terminated or truncated
            returns.append(total)
    return np.array(gaps), returns


def _job(args) -> str:
    task, seed, options, kind, budget, taught = args
    kept = {}
    run_connrl(task, seed, options, kind, setup=lambda agent, env: kept.update(agent=agent), budget=budget,
               taught=taught)
    agent = kept["agent"]
    gaps, returns = gaps_of(agent, gym.make(task), EVAL_EPISODES, EVAL_SEED)
    t = agent.temperature(agent.trials_done)
    q25, q50, q75 = np.percentile(gaps, [25, 50, 75])
    return (f"seed {seed:>4}  gap median {q50:.2f} (quartiles {q25:.2f}, {q75:.2f}) over {gaps.size:,} states  "
            f"below T {np.mean(gaps < t):.2f}  T {t:.2f}  greedy return {np.mean(returns):.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", required=True, choices=list(TASKS))
    ap.add_argument("--kind", default="QCON-T", choices=["QCON-R", "QCON-T"])
    ap.add_argument("--taught", type=int, default=TAUGHT_EPISODES)
    ap.add_argument("--budget", type=int, default=1_000_000)
    ap.add_argument("--base", nargs="*", default=[], help="option=value on top of the shipped settings")
    ap.add_argument("--seeds", nargs="+", type=int, default=[100, 101])
    ap.add_argument("--workers", type=int, default=1)
    args = ap.parse_args()
    if args.workers < 1 or not 10_000 <= args.budget <= 10_000_000 or not 1 <= args.taught <= 100:
        ap.error("--workers must be >= 1, --budget from 10,000 to 10,000,000 steps, --taught from 1 to 100 episodes")
    options = dict(connrl_options(args.task))
    for item in args.base:
        k, sep, v = item.partition("=")
        if not sep:
            ap.error(f"--base {item!r}: give option=value (for example t_end=0.001)")
        options[k] = int(v) if v.lstrip("-").isdigit() else float(v)
    try:
        options_from(options)
    except (ValueError, TypeError) as exc:
        ap.error(str(exc))
    jobs = [(args.task, seed, options, args.kind, args.budget, args.taught) for seed in args.seeds]
    print(f"{args.task}, {args.kind} (taught {args.taught}), {args.budget:,} steps; options {options}")
    with ProcessPoolExecutor(args.workers) as pool:
        for line in pool.map(_job, jobs):
            print(line, flush=True)


if __name__ == "__main__":
    main()
