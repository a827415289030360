"""Relaxation planning and state grouping on the benchmark's tasks, under bench_gymnasium.py's protocol.

    python scripts/own_task/planning_grouping.py --task CartPole-v1 [--seeds 100 101 102 103 104]
        [--arms base plan group:0.1,0.5 ...] [--workers 1]

Arms, each with the shipped settings of the task:

* ``base`` — QCON-R as shipped.
* ``plan`` — QCON-R with relaxation planning (Fig. 3.6, ``connrl.core.planning``) through a *perfect* model: the
  task's own dynamics, stepped from a copy of the true state for every promising action. That bounds what a learned
  model could bring (the thesis measured both, 4.4.3); a model's steps are hypothetical and not counted as
  environment steps, and the table gives them per environment step.
* ``QCON`` and ``QCON+plan`` — the same without experience replay: on-line Q-learning alone and with the perfect
  model's planning, the comparison the thesis made (QCON-M against QCON, 4.4.3).
* ``group:LOW,HIGH`` — QCON-R whose replay groups runs of similar states (6.6.4, ``connrl.core.grouping``) with mu
  drawn from U(LOW, HIGH), in the agent's input units (bounded inputs on [-1, 1]); the table gives the mean group.

The perfect model needs a world whose state can be set: CartPole-v1, Acrobot-v1 and MountainCar-v0 (their
``unwrapped.state``). Development seeds only (100-104), as docs/PERFORMANCE.md reports.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from connrl.core.grouping import check_mu_range
from connrl.core.planning import PlanningConfig, RelaxationPlanner

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_gymnasium import TASKS, run_connrl  # noqa: E402
from sample_efficiency import summary_line  # noqa: E402

SETTABLE = ("CartPole-v1", "Acrobot-v1", "MountainCar-v0")  # worlds whose unwrapped.state sets the whole state


class PerfectModel:
    """The world's own step from its true state, restored after each simulated action; ``calls`` counts them."""

    def __init__(self, env, scaler):
        self.world, self.scaler, self.calls = env.unwrapped, scaler, 0

    def simulate(self, x, actions):
        w = self.world
        saved = (np.array(w.state, copy=True), getattr(w, "steps_beyond_terminated", None))
        outcomes = []
        for a in actions:
            self._restore(saved, copy=True)
            obs, r, terminated, _, _ = w.step(int(a))
            outcomes.append((self.scaler.encode(obs), float(r), bool(terminated)))
        self._restore(saved, copy=False)
        self.calls += len(actions)
        return outcomes

    def _restore(self, saved, copy: bool) -> None:
        self.world.state = saved[0].copy() if copy else saved[0]
        if hasattr(self.world, "steps_beyond_terminated"):  # CartPole warns when stepped past its end
            self.world.steps_beyond_terminated = saved[1]


def _setup(arm: str, tally: dict):
    def setup(agent, env):
        learner = agent.learner
        if arm.endswith("plan"):
            tally["model"] = PerfectModel(env, agent.scaler)
            learner.planner = RelaxationPlanner(tally["model"], PlanningConfig())
        elif arm.startswith("group:"):
            mu = _mu(arm)
            learner.config = dataclasses.replace(
                learner.config, replay=dataclasses.replace(learner.config.replay, grouping=mu))
        tally["learner"] = learner
    return setup


def _job(job):
    task, seed, arm = job
    tally: dict = {}
    result = run_connrl(task, seed, kind="QCON" if arm.startswith("QCON") else "QCON-R", setup=_setup(arm, tally))
    learner = tally["learner"]
    if "model" in tally:
        result["extra"] = tally["model"].calls / max(result["steps"], 1)
    elif arm.startswith("group:"):
        result["extra"] = learner.grouped_steps / max(learner.groups, 1)
    return result


def _mu(arm: str) -> tuple[float, float]:
    """A ``group:LOW,HIGH`` arm's mu range, checked as replay checks it."""
    return check_mu_range(arm.split(":", 1)[1].split(","))


def _arm(text: str) -> str:
    if text in ("base", "plan", "QCON", "QCON+plan"):
        return text
    if text.startswith("group:"):
        try:
            _mu(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(f"{text!r}: give group:LOW,HIGH, for example group:0.1,0.5 ({exc})") \
                from None
        return text
    raise argparse.ArgumentTypeError(f"unknown arm {text!r}; allowed: base, plan, QCON, QCON+plan, group:LOW,HIGH")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", required=True, choices=list(SETTABLE))
    ap.add_argument("--seeds", nargs="+", type=int, default=[100, 101, 102, 103, 104])
    ap.add_argument("--arms", nargs="+", type=_arm, default=["base", "plan", "group:0.1,0.5"])
    ap.add_argument("--workers", type=int, default=1)
    args = ap.parse_args()
    if args.workers < 1:
        ap.error(f"--workers must be 1 or more, got {args.workers}")
    jobs = [(args.task, seed, arm) for arm in args.arms for seed in args.seeds]
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(_job, jobs))
    print(f"{args.task}, QCON-R unless named, {TASKS[args.task][1]:,} steps, seeds {' '.join(map(str, args.seeds))}; "
          "extra: model steps per env step (plan), mean group size (group)")
    print(f"{'arm':<28} {'held':>5} {'median held':>12} {'area':>8} {'at budget':>10} {'lost':>9}   per seed: "
          "held at / greedy at budget")
    n = len(args.seeds)
    for i, arm in enumerate(args.arms):
        rs = results[i * n:(i + 1) * n]
        extra = [r["extra"] for r in rs if "extra" in r]
        line = summary_line(arm, rs, TASKS[args.task][0])
        print(line + (f"   extra {np.mean(extra):.2f}" if extra else ""), flush=True)


if __name__ == "__main__":
    main()
