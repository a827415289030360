"""connrl's QCON-R with its defaults, and SB3's DQN with RL-Zoo's settings when installed, on three classic tasks.

    python benchmarks/bench_gymnasium.py [--tasks CartPole-v1 Acrobot-v1 MountainCar-v0] [--seeds 3]

Per task and seed: the environment steps until a *held solve* -- the greedy policy's mean return over 10 episodes at
or above the task's threshold (CartPole 475, Acrobot -100, MountainCar -110) at five evaluations in a row, one every
5,000 steps, the steps counted at the fifth -- within RL-Zoo's budget for DQN (50k, 100k, 120k); the training wall time
(evaluations excluded) and environment steps per second. connrl's random warm-up (1,000 steps that set its scales) is
counted in its steps and its time, as SB3's ``learning_starts`` steps are in SB3's; connrl evaluates after the trial
that crosses each 5,000 mark, SB3 on the mark. SB3-DQN runs only where ``stable_baselines3`` imports
(``pip install -e ".[bench]"``), with RL-Zoo's DQN hyperparameters (``RL_ZOO_DQN``, copied from rl-baselines3-zoo's
hyperparams/dqn.yml) and one torch thread, as each connrl run has one core; the ratios are printed after both.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import connrl

TASKS = {"CartPole-v1": (475.0, 50_000), "Acrobot-v1": (-100.0, 100_000), "MountainCar-v0": (-110.0, 120_000)}
EVAL_EVERY, EVAL_EPISODES, HELD = 5_000, 10, 5
_ZOO_COMMON = {"policy": "MlpPolicy", "policy_kwargs": {"net_arch": [256, 256]}}
RL_ZOO_DQN = {  # rl-baselines3-zoo hyperparams/dqn.yml (n_timesteps is TASKS' budget)
    "CartPole-v1": dict(learning_rate=2.3e-3, batch_size=64, buffer_size=100_000, learning_starts=1000, gamma=0.99,
                        target_update_interval=10, train_freq=256, gradient_steps=128, exploration_fraction=0.16,
                        exploration_final_eps=0.04),
    "Acrobot-v1": dict(learning_rate=6.3e-4, batch_size=128, buffer_size=50_000, learning_starts=0, gamma=0.99,
                       target_update_interval=250, train_freq=4, gradient_steps=-1, exploration_fraction=0.12,
                       exploration_final_eps=0.1),
    "MountainCar-v0": dict(learning_rate=4e-3, batch_size=128, buffer_size=10_000, learning_starts=1000, gamma=0.98,
                           target_update_interval=600, train_freq=16, gradient_steps=8, exploration_fraction=0.2,
                           exploration_final_eps=0.07),
}


class _Held:
    """Counts the evaluations in a row at the threshold; ``check(steps, returns)`` is False once a solve is held."""

    def __init__(self, threshold: float):
        self.threshold, self.next, self.streak, self.held, self.eval_s = threshold, EVAL_EVERY, 0, None, 0.0

    def due(self, steps: int) -> bool:
        return steps >= self.next

    def check(self, steps: int, returns) -> bool:
        self.next += EVAL_EVERY
        self.streak = self.streak + 1 if float(np.mean(returns)) >= self.threshold else 0
        if self.streak == HELD:
            self.held = steps
            return False
        return True


def run_connrl(task: str, seed: int) -> tuple[int | None, float, int]:
    """(steps to a held solve or None, training seconds, training steps) of QCON-R with its defaults."""
    threshold, budget = TASKS[task]
    env, eval_env = gym.make(task), gym.make(task)
    t0 = time.perf_counter()
    agent = connrl.make_agent(env, "QCON-R", seed=seed)
    warmup = agent.options.warmup_steps  # environment steps too: counted like SB3's learning_starts
    held = _Held(threshold)

    def evaluate(a, _ret):
        if not held.due(warmup + a.steps_done):
            return True
        t1 = time.perf_counter()
        returns = connrl.evaluate(a, eval_env, EVAL_EPISODES, seed=10_000)
        held.eval_s += time.perf_counter() - t1
        return held.check(warmup + a.steps_done, returns)

    agent.learn(budget - warmup, callback=evaluate)
    return held.held, time.perf_counter() - t0 - held.eval_s, warmup + agent.steps_done


def run_sb3(task: str, seed: int) -> tuple[int | None, float, int]:
    """The same for SB3's DQN with RL-Zoo's hyperparameters; greedy = ``deterministic=True``."""
    import torch
    from stable_baselines3 import DQN
    from stable_baselines3.common.callbacks import BaseCallback

    torch.set_num_threads(1)
    threshold, budget = TASKS[task]
    eval_env, held = gym.make(task), _Held(threshold)

    class Evaluate(BaseCallback):
        def _on_step(self) -> bool:
            if not held.due(self.num_timesteps):
                return True
            t0 = time.perf_counter()
            returns = []
            for k in range(EVAL_EPISODES):
                obs, _ = eval_env.reset(seed=10_000 + k)
                done, total = False, 0.0
                while not done:
                    a, _ = self.model.predict(obs, deterministic=True)
                    obs, r, terminated, truncated, _ = eval_env.step(int(a))
                    total, done = total + float(r), terminated or truncated
                returns.append(total)
            held.eval_s += time.perf_counter() - t0
            return held.check(self.num_timesteps, returns)

    model = DQN(env=gym.make(task), seed=seed, device="cpu", verbose=0, **_ZOO_COMMON, **RL_ZOO_DQN[task])
    t0 = time.perf_counter()
    model.learn(budget, callback=Evaluate())
    return held.held, time.perf_counter() - t0 - held.eval_s, int(model.num_timesteps)


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
    learners = {"QCON-R": run_connrl, **({"SB3-DQN": run_sb3} if sb3 else {})}
    summary = {}
    for task in args.tasks:
        for name, run in learners.items():
            held_all, rates = [], []
            for seed in range(args.seeds):
                held, secs, steps = run(task, seed)
                held_all.append(held)
                rates.append(steps / secs)
                print(f"{task:<16} {name:<10} {seed:>4} {held if held else 'not held':>20} {secs:>8.1f} "
                      f"{steps / secs:>9.0f}", flush=True)
            summary[task, name] = (held_all, float(np.mean(rates)))
            print(f"{task:<16} {name} held a solve in {sum(h is not None for h in held_all)} of {args.seeds} seeds "
                  f"within {TASKS[task][1]:,} steps")
    if not sb3:
        print("SB3-DQN: not run (stable_baselines3 is not installed: pip install -e \".[bench]\"); no ratios")
        return
    print("\nratios, connrl QCON-R / SB3-DQN (steps: mean over the seeds where both held; none such: n/a)")
    for task in args.tasks:
        (ours, our_rate), (theirs, their_rate) = summary[task, "QCON-R"], summary[task, "SB3-DQN"]
        both = [(a, b) for a, b in zip(ours, theirs, strict=True) if a is not None and b is not None]
        steps = f"{np.mean([a for a, _ in both]) / np.mean([b for _, b in both]):.2f}x" if both else "n/a"
        ours, theirs = [h for h in ours if h is not None], [h for h in theirs if h is not None]
        print(f"{task:<16} held {len(ours)} vs {len(theirs)} of {args.seeds}; steps to held solve {steps}; "
              f"steps/s {our_rate / their_rate:.1f}x")


if __name__ == "__main__":
    main()
