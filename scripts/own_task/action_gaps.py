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
from bench_gymnasium import (  # noqa: E402
    EVAL_EPISODES,
    TASKS,
    TAUGHT_EPISODES,
    connrl_options,
    policy_returns,
    run_connrl,
)
from sample_efficiency import _pairs, _value  # noqa: E402


def gaps_of(agent, env, episodes: int) -> tuple[np.ndarray, list[float]]:
    """The best-minus-second action-value gap at each state of ``episodes`` greedy episodes (the benchmark's evaluation
    episodes), and their returns. The greedy action is the best value's, as ``agent.predict`` picks it for QCON."""
    gaps = []

    def act(obs) -> int:
        q = agent.learner.q.values(agent.scaler.encode(obs))
        top2 = np.sort(q)[-2:]
        gaps.append(top2[1] - top2[0])
        return int(np.argmax(q))

    with agent.greedy_weights():
        returns = policy_returns(env, act, episodes)
    return np.array(gaps), returns


def _job(args) -> str:
    task, seed, options, kind, budget, taught = args
    kept = {}
    run_connrl(task, seed, options, kind, setup=lambda agent, env: kept.update(agent=agent), budget=budget,
               taught=taught)
    agent = kept["agent"]
    gaps, returns = gaps_of(agent, gym.make(task), EVAL_EPISODES)
    t = agent.temperature(agent.trials_done)
    q25, q50, q75 = np.percentile(gaps, [25, 50, 75])
    return (f"seed {seed:>4}  gap median {q50:.2f} (quartiles {q25:.2f}, {q75:.2f}) over {gaps.size:,} states  "
            f"below T {np.mean(gaps < t):.2f}  T {t:.2f}  greedy return {np.mean(returns):.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", required=True, choices=list(TASKS))
    ap.add_argument("--kind", default="QCON-T", choices=["QCON-R", "QCON-T"])
    ap.add_argument("--taught", type=int, default=TAUGHT_EPISODES,
                    help="teacher episodes (default 3 on every task; the benchmark's: bench_gymnasium.taught_episodes)")
    ap.add_argument("--budget", type=int, default=1_000_000)
    ap.add_argument("--base", nargs="*", default=[], help="option=value on top of the shipped settings")
    ap.add_argument("--seeds", nargs="+", type=int, default=[100, 101])
    ap.add_argument("--workers", type=int, default=1)
    args = ap.parse_args()
    if args.workers < 1:
        ap.error(f"--workers must be 1 or more, got {args.workers}")
    if not 10_000 <= args.budget <= 10_000_000:
        ap.error(f"--budget must be from 10,000 to 10,000,000 steps, got {args.budget:,}")
    if not 1 <= args.taught <= 100:
        ap.error(f"--taught must be from 1 to 100 episodes, got {args.taught}")
    options = {**connrl_options(args.task), **{k: _value(v) for k, v in _pairs(args.base, "--base").items()}}
    try:
        options_from(options)
    except (ValueError, TypeError) as exc:
        ap.error(str(exc))
    jobs = [(args.task, seed, options, args.kind, args.budget, args.taught) for seed in args.seeds]
    print(f"{args.task}, {args.kind} (taught {args.taught}), {args.budget:,} steps; options {options}")
    with ProcessPoolExecutor(args.workers) as pool:
        try:
            for line in pool.map(_job, jobs):
                print(line, flush=True)
        except ValueError as exc:  # a budget the teacher's episodes use up: one line, not a worker's traceback
            raise SystemExit(f"action_gaps.py: error: {exc}") from None


if __name__ == "__main__":
    main()
