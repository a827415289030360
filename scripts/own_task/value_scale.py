"""How connrl.own.api's value scale was chosen (issue 29): QCON-R with the old rule (value_range = max |warm-up reward|
/ (1 - gamma), at least 0.1, never changed) against the new one (connrl.own.value_scale: |r| / (1 - gamma) for
rewards that recur, |r| for one that ends the episode, set by the first non-zero reward when the warm-up saw none,
grown by larger rewards; "new-nogrow" without the growth, "new-h2" / "new-h2-T" with nets spanning twice that), on
development tasks (the rule was chosen on these, seeds 100-102) and on held-out tasks and seeds (never used to
choose: seeds 200-202). A run succeeds when its greedy evaluation return (mean over the task's evaluation episodes,
seeds 500...) reaches the task's threshold; the table gives per-seed returns and the successes, and the first seed's
value_range after the warm-up and at the end (nan: provisional, no non-zero reward seen yet).

python scripts/own_task/value_scale.py [--quick] [--set dev|held-out|all] [--rules old new] [--workers 2] [--seeds
...] [--tasks ...] [--out FILE.json]

--quick runs the small tasks only (a few minutes on 2 cores); without it CartPole-v1, Acrobot-v1, MountainCar-v0,
Taxi-v4 and FrozenLake8x8 are run too, at 50,000 steps each."""

from __future__ import annotations

import argparse
import json
import time
import warnings
from concurrent.futures import ProcessPoolExecutor

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.wrappers import TimeLimit

import connrl
import connrl.own.api


class SparseGrid(gym.Env):
    """An n x n grid, start at (0, 0), goal at (n-1, n-1) worth ``goal`` (ends the episode), ``step`` every other
    step; actions up / down / left / right (walls keep you in place); ``coords``: the observation is (row, col) in a
    Box, else the cell number (Discrete). A TimeLimit of ``limit`` steps."""

    def __init__(self, n=5, goal=1.0, step=0.0, coords=False, walls=()):
        self.n, self.goal, self.step_reward, self.coords, self.walls = n, goal, step, coords, set(walls)
        self.action_space = spaces.Discrete(4)
        self.observation_space = (spaces.Box(0.0, n - 1.0, (2,), np.float64) if coords else spaces.Discrete(n * n))

    def _obs(self):
        return np.array(self.pos, float) if self.coords else self.pos[0] * self.n + self.pos[1]

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.pos = (0, 0)
        return self._obs(), {}

    def step(self, a):
        dr, dc = ((-1, 0), (1, 0), (0, -1), (0, 1))[int(a)]
        r, c = self.pos[0] + dr, self.pos[1] + dc
        if 0 <= r < self.n and 0 <= c < self.n and (r, c) not in self.walls:
            self.pos = (r, c)
        done = self.pos == (self.n - 1, self.n - 1)
        return self._obs(), self.goal if done else self.step_reward, done, False, {}


def grid(limit, **kw):
    return TimeLimit(SparseGrid(**kw), limit)


# name: (make env, steps, threshold on the greedy mean return, evaluation episodes, part of --quick)
DEV = {
    "grid5 (+1 goal)": (lambda: grid(50, n=5), 20_000, 0.99, 1, True),
    "FrozenLake4x4": (lambda: gym.make("FrozenLake-v1", is_slippery=False), 20_000, 0.99, 1, True),
    "CliffWalking": (lambda: TimeLimit(gym.make("CliffWalking-v1"), 200), 30_000, -17, 1, True),
    "grid14 (-0.1/step, +100) w200": (lambda: grid(400, n=14, goal=100.0, step=-0.1), 40_000, 50, 1, True),
    "FrozenLake8x8": (lambda: gym.make("FrozenLake8x8-v1", is_slippery=False), 50_000, 0.99, 1, False),
    "Taxi-v4": (lambda: gym.make("Taxi-v4"), 50_000, 0.0, 20, False),
    "CartPole-v1": (lambda: gym.make("CartPole-v1"), 50_000, 475, 10, False),
    "Acrobot-v1": (lambda: gym.make("Acrobot-v1"), 50_000, -100, 10, False),
    "MountainCar-v0": (lambda: gym.make("MountainCar-v0"), 50_000, -199, 10, False),
}
WALLS7 = [(1, c) for c in range(5)] + [(4, c) for c in range(2, 7)]  # a zig-zag: the goal is 17 steps away
HELD_OUT = {
    "grid7 walls (+1)": (lambda: grid(100, n=7, walls=WALLS7), 30_000, 0.99, 1, True),
    "grid6 (+10 goal)": (lambda: grid(60, n=6, goal=10.0), 20_000, 9.9, 1, True),
    "grid6 (+0.01 goal)": (lambda: grid(60, n=6, goal=0.01), 20_000, 0.0099, 1, True),
    "grid6 xy (+1)": (lambda: grid(60, n=6, coords=True), 20_000, 0.99, 1, True),
    "grid6 (-1/step cost)": (lambda: grid(60, n=6, goal=0.0, step=-1.0), 20_000, -10.5, 1, True),
    "grid6 (-0.01/step, +1)": (lambda: grid(60, n=6, goal=1.0, step=-0.01), 20_000, 0.9, 1, True),
    "FrozenLake4x4 slippery": (lambda: gym.make("FrozenLake-v1"), 50_000, 0.5, 100, False),
    "grid10 (+1 goal)": (lambda: grid(200, n=10), 50_000, 0.99, 1, False),
    "grid16 (-1/step, +1000) w300": (lambda: grid(400, n=16, goal=1000.0, step=-1.0), 50_000, 500, 1, False),
    "grid18 (-0.01/step, +5)": (lambda: grid(500, n=18, goal=5.0, step=-0.01), 50_000, 2.5, 1, False),
}
TASKS = {**DEV, **HELD_OUT}
# make_agent options beside the defaults: "wN" in a name is a warm-up of N steps, short enough that it rarely sees the
# goal, so the range is set by the step costs and must grow when the goal is found
OPTIONS = {name: {"warmup_steps": int(name.rsplit(" w", 1)[1])} for name in TASKS if name.rsplit(" w", 1)[-1].isdigit()}


def old_range_for(step_max, end_max, gamma):
    """The rule before issue 29: every reward taken to recur, at least 1e-3 / (1 - gamma); never provisional."""
    return max(step_max, end_max, 1e-3) / max(1.0 - gamma, 1e-3)


def headroom(h, same_t):
    """The new rule with the nets spanning h times the bound; ``same_t``: the temperature still on Q / bound."""
    def range_for(step_max, end_max, gamma):
        bound = NEW(step_max, end_max, gamma)
        return None if bound is None else h * bound
    return range_for, (1.0 / h if same_t else 1.0), True


def no_growth(self, sizes):
    """Agent._check_range without growth: only a provisional range is set (the old rule's ranges never are)."""
    if not self.range_set:
        CHECK(self, sizes)


NEW, TEMPERATURE, CHECK = connrl.own.api.range_for, connrl.own.api.Agent.temperature, connrl.own.api.Agent._check_range
# name: (range rule, temperature factor, whether larger rewards seen while learning grow the range)
RULES = {"old": (old_range_for, 1.0, False), "new": (NEW, 1.0, True), "new-nogrow": (NEW, 1.0, False),
         "new-h2": headroom(2, False), "new-h2-T": headroom(2, True)}


def one(job):
    task, rule, seed = job
    make, steps, threshold, episodes, _ = TASKS[task]
    connrl.own.api.range_for, t_factor, grow = RULES[rule]  # this worker's rule (make_agent and learn() read it)
    connrl.own.api.Agent._check_range = CHECK if grow else no_growth
    connrl.own.api.Agent.temperature = (TEMPERATURE if t_factor == 1.0 else
                                    lambda self, trial: t_factor * TEMPERATURE(self, trial))
    env = make()
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        agent = connrl.make_agent(env, "QCON-R", seed=seed, **OPTIONS.get(task, {}))
        first = agent.value_range if agent.range_set else float("nan")  # nan: provisional (no reward seen yet)
        agent.learn(steps)
    ret = float(np.mean(connrl.evaluate(agent, env, episodes, seed=500)))
    last = agent.value_range if agent.range_set else float("nan")
    return task, rule, seed, ret, ret >= threshold, first, last, time.process_time() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the small tasks only")
    ap.add_argument("--set", choices=("dev", "held-out", "all"), default="all")
    ap.add_argument("--rules", nargs="+", default=["old", "new"], choices=list(RULES))
    ap.add_argument("--seeds", type=int, nargs="+", default=None, help="default: 100-102 (dev), 200-202 (held-out)")
    ap.add_argument("--tasks", nargs="+", default=None, choices=list(TASKS))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None, help="also write the results as JSON")
    args = ap.parse_args()
    sets = {"dev": [("dev", DEV, [100, 101, 102])], "held-out": [("held-out", HELD_OUT, [200, 201, 202])]}
    sets["all"] = sets["dev"] + sets["held-out"]
    jobs, groups = [], []
    for label, tasks, seeds in sets[args.set]:
        seeds = args.seeds or seeds
        names = [t for t in tasks if (args.tasks is None or t in args.tasks) and (tasks[t][4] or not args.quick)]
        groups.append((label, names, seeds))
        jobs += [(t, r, s) for t in names for r in args.rules for s in seeds]
    results = {}
    with ProcessPoolExecutor(args.workers) as pool:
        for r in pool.map(one, jobs):
            results[r[:3]] = r
            print(f"  {r[0]} {r[1]} seed {r[2]}: {r[3]:.3g} ({'solved' if r[4] else 'not solved'}; range "
                  f"{r[5]:.3g} -> {r[6]:.3g}; {r[7]:.0f} s)", flush=True)
    for label, names, seeds in groups:
        print(f"\n{label} tasks, QCON-R, seeds {seeds}: greedy return per seed, solved / runs, value_range at the "
              "start -> end")
        for t in names:
            _, steps, threshold, _, _ = TASKS[t]
            for rule in args.rules:
                rs = [results[(t, rule, s)] for s in seeds]
                print(f"  {t:<30} {steps // 1000:>3}k  >= {threshold:<7g} {rule:<4} "
                      f"{' '.join(f'{r[3]:8.3g}' for r in rs)}   {sum(r[4] for r in rs)}/{len(rs)}   "
                      f"range {rs[0][5]:.3g} -> {rs[0][6]:.3g}")
    if args.out:
        with open(args.out, "w") as f:
            json.dump([list(r) for r in results.values()], f, indent=1)


if __name__ == "__main__":
    main()
