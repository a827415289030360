"""Training the Ch. 6 behaviour library (``connrl train-behaviours``) and measuring each behaviour where Ch. 6 uses it.

Each behaviour is Ch. 5's QCON-T (``RobotParams``: the thesis's 5.3 values, the calibrated world) trained from scratch
with the thesis's lessons (10 for DK and DP, 5 for WFL and WFR, 6.6.5) for ``TrainingPlan.trials`` trials; DP (and,
our addition, DK) also start a quarter of their trials anywhere, "occasionally trained on locations far away from the
doors" (6.4.3, footnote 4), so their Q-values stay low there. Deterministic given the seed; the four train in
parallel processes.

Where Ch. 6 uses them (``serve_rate``; 200 fixed starts each, greedy, 30 steps as in Ch. 5's tests):
- DP: from subgoals 3, 4, 5 and 6 (Fig. 6.2; +-6 in, any heading), the share that passes the door;
- DK: from within 24 in of subgoal 2, any heading, the share that docks;
- WFL / WFR: from anywhere, the share of steps that earn 8-10 (a forward move with the clearance kept, 5.3.1).
"""

from __future__ import annotations

import json
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from connrl.core.rollout import run_trial
from connrl.envs.robot import Layout, RobotTaskEnv
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS
from connrl.envs.robot.tasks import sample_anywhere
from connrl.experiments.robot import RobotParams, RobotRun
from connrl.experiments.spec import check_types, param
from connrl.experiments.store import environment_info
from connrl.storage import atomic_write_text
from connrl.tasks.behaviours import Behaviour, library_paths, load_library, save_behaviour
from connrl.tasks.robot import TAUGHT_COUNTS


@dataclass(frozen=True)
class TrainingPlan:
    """One behaviour's training: task, trials, taught lessons, and (DP) the share of far-from-door starts."""

    task: str = param(choices=BEHAVIOUR_TASKS)
    trials: int = param(1500, ">=1")
    lessons: int = param(10, ">=0")
    far_share: float = param(0.0, "0..1")

    def __post_init__(self):
        check_types(self)


# A quarter of DK's and DP's trials start anywhere, so that their Q-values, and so their applicability (6.4.3), stay
# low away from the charger and the doors (docs/RECONSTRUCTION.md, "Behaviour library").
PLANS = (TrainingPlan("DK", far_share=0.25), TrainingPlan("DP", far_share=0.25), TrainingPlan("WFL", lessons=5),
         TrainingPlan("WFR", lessons=5))


def train_behaviour(plan: TrainingPlan, seed: int) -> Behaviour:
    """Train one behaviour from scratch; its provenance records the plan, the seed and its final greedy test."""
    p = replace(RobotParams(), task=plan.task, lessons=plan.lessons, trials=plan.trials)
    rng = np.random.default_rng(seed)
    run = RobotRun(p, rng)
    layout = run.env.unwrapped.layout
    spent = 0
    for k in range(p.trials):
        far = plan.far_share > 0 and rng.random() < plan.far_share
        spent += run.train(k, options={"start": sample_anywhere(rng, layout)} if far else None).steps
    meta = {"seed": seed, "trials": plan.trials, "steps": spent, "lessons": plan.lessons, "far_share": plan.far_share,
            "final_test_performance": round(float(run.test()), 4), "params": "RobotParams defaults (5.3)",
            "trainer": "connrl.experiments.behaviours.train_behaviour",
            "code": {k: environment_info()[k] for k in ("connrl", "git_commit")}}
    return Behaviour(plan.task, run.agent.q, p.binary_low, meta)


def pretrain_behaviours(steps: int, rng: np.random.Generator) -> tuple[dict, dict[str, int], dict[str, int]]:
    """Experiment 5 (6.6.5): train each behaviour alone (Ch. 5's QCON-T and task, the thesis's taught lessons) until
    ``steps`` primitive steps are spent; returns the learning agents, the trials and the steps each took."""
    agents, trials, spent_by = {}, {}, {}
    for task in BEHAVIOUR_TASKS:
        run = RobotRun(RobotParams(task=task, lessons=TAUGHT_COUNTS[task]), np.random.default_rng(rng.integers(2**63)))
        spent = k = 0
        while spent < steps:
            spent += run.train(k).steps
            k += 1
        agents[task], trials[task], spent_by[task] = run.agent, k, spent
    return agents, trials, spent_by


# The thesis's experimental steps to a good policy for each behaviour (8.5's table: 2,000 / 2,000 / 1,500 / 1,500, 7,000
# in all): the budget within which ``train_within_budget`` trains a run's own behaviours (6.7 counts these steps in
# Exp. 3's total of about 40,000)
THESIS_BEHAVIOUR_STEPS = {"DK": 2000, "DP": 2000, "WFL": 1500, "WFR": 1500}
MAX_TRIAL_STEPS = 30  # a behaviour's trial ends after at most 30 primitive steps (5.4)


def budget_split(total: int) -> dict[str, int]:
    """``total`` primitive steps shared among the four behaviours in 8.5's proportions (7,000 -> the thesis's own)."""
    whole = sum(THESIS_BEHAVIOUR_STEPS.values())
    return {t: int(round(total * n / whole)) for t, n in THESIS_BEHAVIOUR_STEPS.items()}


def train_within_budget(budget: dict[str, int],
                        rng: np.random.Generator) -> tuple[dict, dict[str, int], dict[str, int]]:
    """Train the four behaviours from scratch as the shipped library was (``PLANS``: Ch. 5's QCON-T and task, the
    thesis's taught lessons, DK's and DP's far-from-goal starts) but stop each before its trials could pass its
    ``budget`` of primitive steps (a trial is started only while ``MAX_TRIAL_STEPS`` more fit). The temperature
    schedule is Ch. 5's 300-trial one, as in the runs 8.5's numbers are read from. Returns the behaviours (frozen
    copies of the learned Q-nets), the trials and the primitive steps each took."""
    out, trials, spent_by = {}, {}, {}
    for plan in PLANS:
        p = replace(RobotParams(), task=plan.task, lessons=plan.lessons)
        task_rng = np.random.default_rng(rng.integers(2**63))
        run = RobotRun(p, task_rng)
        layout = run.env.unwrapped.layout
        spent = k = 0
        while spent + MAX_TRIAL_STEPS <= budget[plan.task]:
            far = plan.far_share > 0 and task_rng.random() < plan.far_share
            spent += run.train(k, options={"start": sample_anywhere(task_rng, layout)} if far else None).steps
            k += 1
        out[plan.task] = Behaviour(plan.task, run.agent.q, p.binary_low, {"trials": k, "steps": spent})
        trials[plan.task], spent_by[plan.task] = k, spent
    return out, trials, spent_by


def _serve_starts(task: str, rng: np.random.Generator, layout: Layout, n: int) -> list[tuple]:
    starts = []
    while len(starts) < n:
        if task == "DP":
            cx, cy = layout.subgoals[str(int(rng.integers(3, 7)))]
            x, y = cx + rng.uniform(-6, 6), cy + rng.uniform(-6, 6)
        elif task == "DK":
            r, a = 24.0 * np.sqrt(rng.random()), rng.uniform(0, 2 * np.pi)
            x, y = layout.subgoals["2"][0] + r * np.cos(a), layout.subgoals["2"][1] + r * np.sin(a)
        else:
            x, y, _ = sample_anywhere(rng, layout)
        if layout.is_free(x, y):
            starts.append((float(x), float(y), float(rng.uniform(0, 360))))
    return starts


def serve_rate(b: Behaviour, seed: int = 0, n: int = 200) -> float:
    """The behaviour where Ch. 6 uses it (module docstring): success share (DP, DK) or share of 8-10 steps (WF)."""
    rng = np.random.default_rng(seed)
    env = RobotTaskEnv(b.task, binary_low=b.binary_low)
    good = steps = 0
    for start in _serve_starts(b.task, rng, env.layout, n):
        seed = int(rng.integers(2**31))  # one trial seed per start (wall following draws its own below)
        if b.task in ("DP", "DK"):
            stats = run_trial(env, b, trial=0, learning=False, seed=seed, options={"start": start})
            good += bool(stats.info.get("success"))
        else:
            good += _good_wf_steps(env, b, start, rng)
            steps += 30
    return good / (steps if steps else n)


def _good_wf_steps(env, b: Behaviour, start, rng) -> int:
    obs, _ = env.reset(seed=int(rng.integers(2**31)), options={"start": start})
    good = 0
    for _ in range(30):
        obs, r, _, _, _ = env.step(b.act(obs))
        good += r >= 8
    return good


def _train_one(args) -> tuple[str, dict]:
    plan, seed, directory = args
    b = train_behaviour(plan, seed)
    save_behaviour(b, library_paths(directory)[plan.task])
    return plan.task, b.meta


def train_library(directory, seed: int = 0, trials: int | None = None, workers: int = 2) -> dict:
    """Train the four behaviours (seeds ``seed`` .. ``seed + 3``), store them in ``directory`` with an index
    (``library.json``) holding each one's provenance and serve rate."""
    directory = Path(directory)
    plans = [replace(p, trials=trials) if trials else p for p in PLANS]
    jobs = [(plan, seed + i, directory) for i, plan in enumerate(plans)]
    with ProcessPoolExecutor(max_workers=max(1, workers)) as pool:
        metas = dict(pool.map(_train_one, jobs))
    lib = load_library(directory)  # the stored files, read back as a user would
    index = {t: {**metas[t], "serve_rate": round(serve_rate(lib[t], seed), 4)} for t in lib}
    atomic_write_text(directory / "library.json", json.dumps({"format": 1, "behaviours": index}, indent=1) + "\n")
    return index
