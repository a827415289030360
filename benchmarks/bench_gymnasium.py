"""connrl's QCON-R with its defaults, and SB3's DQN with RL-Zoo's settings when installed, on three classic tasks.

    python benchmarks/bench_gymnasium.py [--tasks CartPole-v1 Acrobot-v1 MountainCar-v0] [--seeds 3]

Per task and seed: the environment steps until a *held solve* -- the greedy policy's mean return over 10 episodes at
or above the task's threshold (CartPole 475, Acrobot -100, MountainCar -110) at five evaluations in a row, one every
5,000 steps, the steps counted at the fifth -- within RL-Zoo's budget for DQN (50k, 100k, 120k); the training wall time
(evaluations excluded) and environment steps per second. SB3-DQN runs only where ``stable_baselines3`` imports
(``pip install -e ".[bench]"``); its rows and the ratios are then printed beside ours.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import connrl

TASKS = {"CartPole-v1": (475.0, 50_000), "Acrobot-v1": (-100.0, 100_000), "MountainCar-v0": (-110.0, 120_000)}
EVAL_EVERY, EVAL_EPISODES, HELD = 5_000, 10, 5


def run_connrl(task: str, seed: int) -> tuple[int | None, float, int]:
    """(steps to a held solve or None, training seconds, training steps) of QCON-R with its defaults."""
    threshold, budget = TASKS[task]
    env, eval_env = gym.make(task), gym.make(task)
    agent = connrl.make_agent(env, "QCON-R", seed=seed)
    state = {"next": EVAL_EVERY, "streak": 0, "held": None, "eval_s": 0.0}

    def evaluate(a, _ret):
        if a.steps_done < state["next"]:
            return True
        state["next"] += EVAL_EVERY
        t0 = time.perf_counter()
        mean = float(np.mean(connrl.evaluate(a, eval_env, EVAL_EPISODES, seed=10_000)))
        state["eval_s"] += time.perf_counter() - t0
        state["streak"] = state["streak"] + 1 if mean >= threshold else 0
        if state["streak"] == HELD:
            state["held"] = a.steps_done
            return False
        return True

    t0 = time.perf_counter()
    agent.learn(budget, callback=evaluate)
    return state["held"], time.perf_counter() - t0 - state["eval_s"], agent.steps_done


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="*", default=list(TASKS), choices=list(TASKS))
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    try:
        import stable_baselines3  # noqa: F401
        sb3 = True
    except ImportError:
        sb3 = False
    print(f"{'task':<16} {'learner':<10} {'seed':>4} {'steps to held solve':>20} {'train s':>8} {'steps/s':>9}")
    for task in args.tasks:
        held_all = []
        for seed in range(args.seeds):
            held, secs, steps = run_connrl(task, seed)
            held_all.append(held)
            print(f"{task:<16} {'QCON-R':<10} {seed:>4} {held if held else 'not held':>20} {secs:>8.1f} "
                  f"{steps / secs:>9.0f}", flush=True)
        print(f"{task:<16} QCON-R held a solve in {sum(h is not None for h in held_all)} of {args.seeds} seeds "
              f"within {TASKS[task][1]:,} steps")
    if not sb3:
        print("SB3-DQN: not run (stable_baselines3 is not installed: pip install -e \".[bench]\"); no ratios")


if __name__ == "__main__":
    main()
