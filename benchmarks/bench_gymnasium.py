"""connrl's QCON-R with its defaults, and SB3's DQN with RL-Zoo's settings and with SB3's own defaults when installed.

    python benchmarks/bench_gymnasium.py [--tasks CartPole-v1 Acrobot-v1 MountainCar-v0] [--seeds 3]
                                         [--sb3 zoo default]

Per task and seed: the environment steps until a *held solve* -- the greedy policy's mean return over 10 episodes at
or above the task's threshold (CartPole 475, Acrobot -100, MountainCar -110) at five evaluations in a row, one every
5,000 steps, the steps counted at the fifth -- within RL-Zoo's budget for DQN (50k, 100k, 120k); the training wall time
(evaluations excluded) as wall and CPU seconds, environment steps per second by each, and the greedy return at the
last evaluation (the held one, or the one at the budget). connrl's random warm-up (1,000 steps that set its scales) is
counted in its steps and its time, as SB3's ``learning_starts`` steps are in SB3's; connrl evaluates after the trial
that crosses each 5,000 mark, SB3 on the mark. SB3's DQN runs only where ``stable_baselines3`` imports
(``pip install -e ".[bench]"``), on one torch thread, as each connrl run has one core, twice over (``--sb3`` picks):
``SB3-zoo`` with RL-Zoo's DQN hyperparameters (``RL_ZOO_DQN``, copied from rl-baselines3-zoo's hyperparams/dqn.yml)
and ``SB3-default`` as ``DQN("MlpPolicy", env, seed=seed)``, nothing else set (SB3's defaults: learning rate 1e-4,
buffer 1,000,000, learning_starts 100, batch 32, train_freq 4, one gradient step, target update every 10,000 steps,
exploration 1 -> 0.05 over the first 10 %, net 64-64). The ratios of QCON-R's speed to each follow the table.
"""

from __future__ import annotations

import argparse
import time
from functools import partial
from typing import NamedTuple

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
    """Counts the evaluations in a row at the threshold; ``check(steps, returns)`` is False once a solve is held.
    ``eval_s`` / ``eval_cpu`` add up the evaluations' wall and CPU seconds, ``last`` is the latest greedy mean."""

    def __init__(self, threshold: float):
        self.threshold, self.next, self.streak, self.held = threshold, EVAL_EVERY, 0, None
        self.eval_s, self.eval_cpu, self.last = 0.0, 0.0, float("nan")

    def timed(self, evaluate):
        """``evaluate()``'s returns, its wall and CPU time kept apart from training's."""
        t0, c0 = time.perf_counter(), time.process_time()
        returns = evaluate()
        self.eval_s += time.perf_counter() - t0
        self.eval_cpu += time.process_time() - c0
        return returns

    def due(self, steps: int) -> bool:
        return steps >= self.next

    def check(self, steps: int, returns) -> bool:
        self.next += EVAL_EVERY
        self.last = float(np.mean(returns))
        self.streak = self.streak + 1 if self.last >= self.threshold else 0
        if self.streak == HELD:
            self.held = steps
            return False
        return True


class Result(NamedTuple):
    held: int | None  # steps to a held solve, None if not within the budget
    greedy: float  # greedy mean return at the last evaluation
    wall: float  # training seconds (evaluations excluded)
    cpu: float  # training CPU seconds of this process (evaluations excluded)
    steps: int  # training environment steps


def run_connrl(task: str, seed: int) -> Result:
    """QCON-R with its defaults."""
    threshold, budget = TASKS[task]
    env, eval_env = gym.make(task), gym.make(task)
    t0, c0 = time.perf_counter(), time.process_time()
    agent = connrl.make_agent(env, "QCON-R", seed=seed)
    warmup = agent.options.warmup_steps  # environment steps too: counted like SB3's learning_starts
    held = _Held(threshold)

    def evaluate(a, _ret):
        if not held.due(warmup + a.steps_done):
            return True
        returns = held.timed(lambda: connrl.evaluate(a, eval_env, EVAL_EPISODES, seed=10_000))
        return held.check(warmup + a.steps_done, returns)

    agent.learn(budget - warmup, callback=evaluate)
    return Result(held.held, held.last, time.perf_counter() - t0 - held.eval_s,
                  time.process_time() - c0 - held.eval_cpu, warmup + agent.steps_done)


def run_sb3(task: str, seed: int, zoo: bool) -> Result:
    """The same for SB3's DQN, with RL-Zoo's hyperparameters (``zoo``) or SB3's defaults; greedy =
    ``deterministic=True``."""
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
            return held.check(self.num_timesteps, held.timed(self.greedy_returns))

        def greedy_returns(self) -> list[float]:
            returns = []
            for k in range(EVAL_EPISODES):
                obs, _ = eval_env.reset(seed=10_000 + k)
                done, total = False, 0.0
                while not done:
                    a, _ = self.model.predict(obs, deterministic=True)
                    obs, r, terminated, truncated, _ = eval_env.step(int(a))
                    total, done = total + float(r), terminated or truncated
                returns.append(total)
            return returns

    settings = {**_ZOO_COMMON, **RL_ZOO_DQN[task]} if zoo else {"policy": "MlpPolicy"}
    # device="cpu" is what "auto" picks on a machine without CUDA; verbose=0 only silences it
    model = DQN(env=gym.make(task), seed=seed, device="cpu", verbose=0, **settings)
    t0, c0 = time.perf_counter(), time.process_time()
    model.learn(budget, callback=Evaluate())
    return Result(held.held, held.last, time.perf_counter() - t0 - held.eval_s,
                  time.process_time() - c0 - held.eval_cpu, int(model.num_timesteps))


SB3_RUNS = {"zoo": ("SB3-zoo", True), "default": ("SB3-default", False)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="*", default=list(TASKS), choices=list(TASKS))
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--sb3", nargs="*", default=list(SB3_RUNS), choices=list(SB3_RUNS),
                    help="SB3 DQN references: RL-Zoo's settings, SB3's defaults (default: both; none: QCON-R only)")
    args = ap.parse_args()
    try:
        import stable_baselines3
        import torch
        sb3 = [SB3_RUNS[k] for k in args.sb3]
        print(f"stable-baselines3 {stable_baselines3.__version__}, torch {torch.__version__}, one torch thread; "
              f"seeds 0-{args.seeds - 1}")
    except ImportError:
        sb3 = []
    learners = {"QCON-R": run_connrl, **{name: partial(run_sb3, zoo=zoo) for name, zoo in sb3}}
    print(f"{'task':<16} {'learner':<12} {'seed':>4} {'held at':>9} {'greedy':>8} {'wall s':>7} {'cpu s':>7} "
          f"{'steps/s wall':>13} {'steps/s cpu':>12}")
    summary = {}
    for task in args.tasks:
        for name, run in learners.items():
            results = []
            for seed in range(args.seeds):
                r = run(task, seed)
                results.append(r)
                print(f"{task:<16} {name:<12} {seed:>4} {r.held if r.held else 'not held':>9} {r.greedy:>8.1f} "
                      f"{r.wall:>7.1f} {r.cpu:>7.1f} {r.steps / r.wall:>13.0f} {r.steps / r.cpu:>12.0f}", flush=True)
            summary[task, name] = results
            print(f"{task:<16} {name} held a solve in {sum(r.held is not None for r in results)} of {args.seeds} "
                  f"seeds within {TASKS[task][1]:,} steps; greedy return at the last evaluation "
                  f"{' / '.join(f'{r.greedy:.1f}' for r in results)}")
    if not sb3:
        if not args.sb3:
            print("SB3-DQN: not run (--sb3 names none); no ratios")
        else:
            print("SB3-DQN: not run (stable_baselines3 is not installed: pip install -e \".[bench]\"); no ratios")
        return
    print("\nratios, connrl QCON-R / SB3 DQN (steps/s: mean over the seeds; steps to held solve: mean over the seeds "
          "where both held, none such: n/a)")
    for task in args.tasks:
        ours = summary[task, "QCON-R"]
        for name, _ in sb3:
            theirs = summary[task, name]
            both = [(a.held, b.held) for a, b in zip(ours, theirs, strict=True) if a.held and b.held]
            steps = f"{np.mean([a for a, _ in both]) / np.mean([b for _, b in both]):.2f}x" if both else "n/a"
            held_ours, held_theirs = (sum(r.held is not None for r in rs) for rs in (ours, theirs))
            cpu, wall = (float(np.mean([r.steps / getattr(r, t) for r in ours]) /
                               np.mean([r.steps / getattr(r, t) for r in theirs])) for t in ("cpu", "wall"))
            print(f"{task:<16} vs {name:<12} held {held_ours} vs {held_theirs} of {args.seeds}; steps to held solve "
                  f"{steps}; steps/s cpu {cpu:.1f}x, wall {wall:.1f}x")


if __name__ == "__main__":
    main()
