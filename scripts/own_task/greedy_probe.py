"""What a connrl learner does on a Gymnasium task as it learns: training and greedy returns along the way, then the
greedy policy's episodes (length, return, actions taken) and its values at a start state.

    python scripts/own_task/greedy_probe.py --task LunarLander-v3 --seed 203 [--steps 100000] [--every 10000]
        [--kind QCON-R] [--option value_range=300 ...]

The options are the shipped settings file's entry for the task (connrl/data/hyperparams/qcon-r.yml) with
``--option`` on top, as in bench_gymnasium.py; the greedy returns are over evaluation seeds 10,000-10,009, the
benchmark's. docs/PERFORMANCE.md ("Sample efficiency against SB3-DQN") quotes it for the causes it names.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np

import connrl
from connrl.own.api import options_from

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sample_efficiency import _pairs, _value  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from bench_gymnasium import EVAL_SEED, TASKS, connrl_options  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", required=True, choices=list(TASKS))
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--steps", type=int, default=None, help="default: the benchmark's budget for the task")
    ap.add_argument("--every", type=int, default=10_000)
    ap.add_argument("--kind", default="QCON-R", choices=["QCON", "QCON-R"], help="a memoryless Q-learner")
    ap.add_argument("--option", nargs="*", default=[])
    args = ap.parse_args()
    if args.every < 1 or (args.steps is not None and args.steps < 1):
        ap.error("--every and --steps must be whole numbers >= 1")
    options = {**connrl_options(args.task), **{k: _value(v) for k, v in _pairs(args.option, "--option").items()}}
    try:  # every option checked before anything runs, as sample_efficiency.py checks its rows
        options_from(options)
    except (ValueError, TypeError) as exc:
        ap.error(str(exc))
    steps = args.steps or TASKS[args.task][1]
    env, eval_env = gym.make(args.task), gym.make(args.task)
    agent = connrl.make_agent(env, args.kind, seed=args.seed, **options)
    print(f"{args.task}, {args.kind}, seed {args.seed}, options {options or 'the defaults'}; value range "
          f"{agent.value_range:.4g} after the warm-up of {agent.options.warmup_steps} steps")
    returns: list[float] = []
    while agent.steps_done < steps - agent.options.warmup_steps:
        agent.learn(min(args.every, steps - agent.options.warmup_steps - agent.steps_done),
                    callback=lambda _a, ret: returns.append(ret) is None)
        greedy = connrl.evaluate(agent, eval_env, 10, seed=EVAL_SEED)
        print(f"steps {agent.options.warmup_steps + agent.steps_done:>7}: {agent.trials_done:>4} trials, training "
              f"return (last 10 trials) {np.mean(returns[-10:]):8.1f}, greedy {np.mean(greedy):8.1f}, value range "
              f"{agent.value_range:.4g}")
    n = int(env.action_space.n)
    for k in range(3):
        obs, _ = eval_env.reset(seed=EVAL_SEED + k)
        done, total, actions = False, 0.0, []
        while not done:
            a = agent.predict(obs)
            actions.append(a)
            obs, r, terminated, truncated, _ = eval_env.step(a)
            total, done = total + float(r), terminated or truncated
        print(f"greedy episode {k}: {len(actions)} steps, return {total:.1f}, {'terminated' if terminated else 'cut'}; "
              f"actions taken {np.bincount(actions, minlength=n).tolist()}")
    start, _ = eval_env.reset(seed=EVAL_SEED)
    q = agent.learner.q.values(agent.scaler.encode(start))
    print(f"values of the actions at the first evaluation start: {np.round(q, 1).tolist()}")


if __name__ == "__main__":
    main()
