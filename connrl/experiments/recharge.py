"""Ch. 6: learning to recharge over learned behaviours (Experiments 2 and 3, Fig. 6.6).

Protocol (6.6): each run learns Q(state, behaviour) (``connrl.agents.behaviour_level.BehaviourQCON``) on top of the
shipped behaviour library, choosing a behaviour on every primitive step (``connrl.tasks.recharge.BehaviourEnv``).
A trial starts in room A, B or C (a room drawn uniformly, then a free place in it, any heading) and ends on docking or
after 200 primitive steps. Before the first trial and after every 10 the greedy policy is tested on fixed tasks, the
same number from each room; performance = reinforcement per primitive step over them, overall and per start room.
Experiment 2 weights the choice by applicability only (W = 0 / 1); Experiment 3 adds the persistence rule (0 / 100 /
1). The thesis's other settings (6.6): 16 inputs (6.4.2), 8 hidden units, lr 0.05, gamma 0.99, lambda 0.8,
T 0.05 -> 0.02, about 60 lessons replayed per trial, P_l from 0 (latest) to 0.02 by recency. Values it does not give
are ours (R; docs/RECONSTRUCTION.md, "High-level learner"): Ch. 5's momentum, memory size, on-line learning; the
initial weights, the X-Y inputs' scale and replay from the first trial, chosen on development seeds for room B; the
test tasks.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from connrl.core.rollout import run_trial
from connrl.envs.robot import Layout
from connrl.envs.robot.recharge import ROOMS, sample_in_room
from connrl.envs.robot.teachers import teach_chg
from connrl.experiments.behaviours import THESIS_BEHAVIOUR_STEPS, budget_split, pretrain_behaviours, train_within_budget
from connrl.experiments.protocol import train_and_test
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant, override, param
from connrl.tasks import recharge_play, recharge_train
from connrl.tasks.behaviours import Behaviour
from connrl.tasks.recharge import (  # noqa: F401  (the parameters, re-exported)
    SHIPPED_LIBRARY,
    TARGET_MAX,
    BehaviourEnv,
    RechargeParams,
    make_high_level_agent,
    make_recharge_env,
)
from connrl.tasks.recharge_together import TrainingBehaviourEnv

LAYOUT = Layout.load("default")  # where the test tasks are drawn



def _test(env, agent, tasks, seeds) -> dict[str, tuple[float, int, int, int]]:
    """Per room: (total reinforcement, steps, dockings, collisions) of the greedy policy on the fixed tasks."""
    out = {r: [0.0, 0, 0, 0] for r in ROOMS}
    fast = recharge_play.compiled(env, agent)  # the same plays, compiled (connrl.tasks.recharge_play)
    recurrent = not fast and recharge_train.compiled_greedy(env, agent)  # Ch. 8's recurrent-Q
    flat = not fast and not recurrent and recharge_play.compiled_flat(env, agent)
    for (room, start), s in zip(tasks, seeds, strict=True):
        if fast:
            stats, hits = recharge_play.greedy_play(env, agent, int(s), start)
        elif recurrent:
            stats, hits = recharge_train.greedy_play(env, agent, int(s), start)
        elif flat:
            stats, hits = recharge_play.greedy_play_flat(env, agent, int(s), start)
        else:
            collided = []
            stats = run_trial(env, agent, trial=0, learning=False, seed=int(s), options={"start": start},
                              on_step=lambda info, c=collided: c.append(info["collision"]))
            hits = sum(collided)
        out[room][0] += stats.total_reward
        out[room][1] += stats.steps
        out[room][2] += bool(stats.info.get("success"))
        out[room][3] += hits
    return {r: tuple(v) for r, v in out.items()}


def run_rooms(p, rng: np.random.Generator, make_env, make_agent, progress=lambda done, total: None,
              after_trial=lambda env: None):
    """The Ch. 6 protocol (module docstring) for any world and agent: fixed greedy test tasks per start room, tested
    before the first trial and every ``p.test_every``; ``after_trial(env)`` follows each training trial. Returns
    (RunResult, agent)."""
    task_rng = np.random.default_rng(rng.integers(2**63))  # first, so every experiment of a seed tests alike
    tasks = [(r, sample_in_room(task_rng, LAYOUT, r)) for r in ROOMS for _ in range(p.tests_per_room)]
    seeds = task_rng.integers(2**31, size=len(tasks))
    env, test_env = make_env(p), make_env(p)
    world = getattr(test_env, "world", test_env)
    agent = make_agent(p, rng)
    env.reset(seed=int(rng.integers(2**31)))
    xs, ys, rows = [], [], []
    spent = 0  # primitive steps of the learning trials so far

    def test(n):
        by_room = _test(test_env, agent, tasks, seeds)
        total, steps = sum(v[0] for v in by_room.values()), sum(v[1] for v in by_room.values())
        xs.append(n)
        ys.append(total / steps)
        rows.append({"trials": n, "performance": total / steps, "train_steps": spent,
                     "collisions": sum(v[3] for v in by_room.values()) / steps,
                     **{f"perf_{r}": v[0] / v[1] for r, v in by_room.items()},
                     **{f"docked_{r}": v[2] / p.tests_per_room for r, v in by_room.items()}})

    def train(k):
        nonlocal spent
        stats = recharge_train.learning_play(env, agent, trial=k)
        spent += stats.steps
        after_trial(env)
        return stats

    train_and_test(p.trials, train, test, test_every=p.test_every, test_first=True, progress=progress, agent=agent)
    last = rows[-3:]
    metrics = {"final_performance": float(np.mean(ys[-3:])), "mean_performance": float(np.mean(ys)),
               **{f"final_docked_{r}": float(np.mean([row[f"docked_{r}"] for row in last])) for r in ROOMS},
               "collision_share": float(np.mean([row["collisions"] for row in last])),
               "teacher_performance": _teacher(world, tasks, seeds), "train_steps": float(spent)}
    extra = {}
    if p.paths:  # Fig. 6.7: greedy solution paths after the last trial, the first tasks of each room
        picks = [i for r in ROOMS for i in [k for k, t in enumerate(tasks) if t[0] == r][:p.paths]]
        extra["paths"] = [_path(test_env, agent, tasks[i], seeds[i]) for i in picks]
    return RunResult(xs, ys, metrics, rows, extra), agent


def _teacher(world, tasks, seeds) -> float:
    """The scripted recharging teacher on the run's test tasks, reinforcement per step: a route a person might
    drive, the near-optimal reference of Fig. 6.6."""
    total = steps = 0
    for (_, start), s in zip(tasks, seeds, strict=True):
        lesson = teach_chg(world, start, seed=int(s))
        total += sum(step[2] for step in lesson)
        steps += len(lesson)
    return total / steps


def _path(env, agent, task, seed) -> dict:
    room, start = task
    chosen = []
    stats = run_trial(env, agent, trial=0, learning=False, seed=int(seed), options={"start": start},
                      on_step=lambda info: chosen.append(info.get("behaviour")))
    return {"room": room, "poses": [[round(v, 1) for v in pose] for pose in env.trace], "behaviours": chosen,
            "success": bool(stats.info.get("success"))}


def run_recharge(p: RechargeParams, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    if p.pretrain_steps:  # Exp. 5: fresh behaviours, pre-trained briefly, learning on beside the high level
        world = {"max_steps": p.max_steps, "step_scale": p.step_scale, "success_reward": p.success_reward,
                 "xy_scale": p.xy_scale}
        made = {}

        def make_env(p):  # run_rooms makes the training world first (pre-training the behaviours), then the test one
            if not made:
                made["agents"], made["trials"], made["spent"] = pretrain_behaviours(p.pretrain_steps, rng)
                return TrainingBehaviourEnv(made["agents"], start_trials=made["trials"], **world)
            return BehaviourEnv({t: Behaviour(t, a.q) for t, a in made["agents"].items()}, **world)

        result, agent = run_rooms(p, rng, make_env, make_high_level_agent, progress,
                                  after_trial=lambda env: env.learn_behaviours())
        result.metrics.update({f"pretrain_trials_{t}": float(k) for t, k in made["trials"].items()})
        result.metrics["pretrain_steps"] = float(sum(made["spent"].values()))
        return result
    result, agent = run_rooms(p, rng, make_recharge_env, make_high_level_agent, progress)
    if p.grouping:
        result.metrics["mean_group_size"] = agent.grouped_steps / max(agent.groups, 1)
    return result


@dataclass(frozen=True)
class OwnLibraryParams(RechargeParams):
    """Exp. 3 over behaviours each run trains for itself within ``library_steps`` primitive steps (shared in 8.5's
    proportions, ``connrl.experiments.behaviours.budget_split``) before the high-level learning, instead of the
    shipped library (1,500 trials a behaviour, one draw shared by every run). A class of its own so that the other
    Ch. 6 experiments' parameters, and so their run folders, stay as they are."""

    library_steps: int = param(sum(THESIS_BEHAVIOUR_STEPS.values()), ">=1", "8.5: 2,000 + 2,000 + 1,500 + 1,500")

    def __post_init__(self):
        super().__post_init__()  # check_types(self) included
        if self.pretrain_steps:
            raise ValueError("parameter pretrain_steps (Exp. 5) does not apply: these behaviours are trained first, "
                             "then frozen")


def run_own_library(p: OwnLibraryParams, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    """The Ch. 6 protocol (``run_rooms``; the same test tasks as Exp. 3 on the same seed) over a library this run
    trains first (``train_within_budget``), frozen during the high-level learning as the shipped one is."""
    world = {"max_steps": p.max_steps, "step_scale": p.step_scale, "success_reward": p.success_reward,
             "xy_scale": p.xy_scale}
    made = {}

    def make_env(p):  # run_rooms makes the training world first (training the behaviours), then the test one
        if not made:
            made["lib"], made["trials"], made["spent"] = train_within_budget(budget_split(p.library_steps), rng)
        return BehaviourEnv(made["lib"], **world)

    result, _ = run_rooms(p, rng, make_env, make_high_level_agent, progress)
    result.metrics.update({f"library_trials_{t}": float(k) for t, k in made["trials"].items()})
    result.metrics.update({f"library_steps_{t}": float(k) for t, k in made["spent"].items()})
    result.metrics["library_steps"] = float(sum(made["spent"].values()))
    result.metrics["total_steps"] = result.metrics["library_steps"] + result.metrics["train_steps"]
    return result


def _q(name, text, better="higher"):
    return Quantity(name, text, better, "6.6")


QUANTITIES = (_q("final_performance", "reinforcement per primitive step, mean of the last 3 tests"),
              _q("mean_performance", "reinforcement per primitive step over all tests (area under the curve)"),
              *(_q(f"final_docked_{r}", f"share of test tasks from room {r} docked, last 3 tests") for r in ROOMS),
              Quantity("collision_share", "share of test steps that collide, last 3 tests", "lower", "6.6.1"),
              _q("teacher_performance", "the scripted teacher on the same test tasks (near-optimal reference)"),
              Quantity("train_steps", "primitive steps of the learning trials (6.7's experimental steps)",
                       section="6.7"))
GROUPING = Quantity("mean_group_size", "primitive steps per group in replay (thesis: about 11)", section="6.6.4")

OWN_LIBRARY = (*(Quantity(f"library_trials_{t}", f"{t}'s training trials within its budget", section="8.5")
                 for t in THESIS_BEHAVIOUR_STEPS),
               *(Quantity(f"library_steps_{t}", f"{t}'s training steps (budget: 8.5's {n:,})", section="8.5")
                 for t, n in THESIS_BEHAVIOUR_STEPS.items()),
               Quantity("library_steps", "primitive steps of the four behaviours' training", section="6.7"),
               Quantity("total_steps", "behaviours' training + high-level learning steps (6.7: about 40,000)",
                        section="6.7"))

STATED_GROUPING = "Exp. 4, state grouping at 6.6.4's mu ~ U(0.5, 2.5), lambda 0.8"
PROFILES = {"tiny": {"runs": 1, "trials": 2, "test_every": 1, "tests_per_room": 1, "lessons_per_trial": 2,
                     "max_steps": 20},
            "quick": {"runs": 2, "trials": 60, "tests_per_room": 5}, "full": {"runs": 7}}

CHAPTER = 6  # the thesis chapter of these experiments (`connrl reproduce --chapters`)
EXPERIMENTS = [
    ExperimentSpec(
        name="recharge-behaviours", title="Exps 2 and 3: recharging over learned behaviours, without and with the "
        "persistence rule", section="6.6.2, 6.6.3 Fig. 6.6", run="connrl.experiments.recharge:run_recharge",
        params=override(RechargeParams(), {"paths": 1}, "experiment recharge-behaviours"), profiles=PROFILES,
        variants=(Variant("Exp. 2: W = 0/1", {"persistence": False}),
                  Variant("Exp. 3: persistence rule", {"persistence": True})),
        quantities=QUANTITIES, x_label="trials", y_label="reinforcement per primitive step (greedy tests)",
        description="the shipped behaviour library (connrl train-behaviours); thesis: Exp. 3 near-optimal from all "
                    "rooms within 60 trials, from A and C within 20; Exp. 2 poor at 150"),
    ExperimentSpec(
        name="recharge-long-delay", title="Exp. 4: primitive steps shrunk to a fifth, without and with state "
        "grouping", section="6.6.4 Fig. 6.6", run="connrl.experiments.recharge:run_recharge",
        params=override(RechargeParams(), {"step_scale": 0.2, "max_steps": 1000, "success_reward": 500.0,
                                           "gamma": 0.998}, "experiment recharge-long-delay"),
        profiles={**PROFILES, "tiny": {**PROFILES["tiny"], "max_steps": 40}},
        variants=(Variant("Exp. 4, no grouping, lambda 0.9", {"lam": 0.9}),
                  # mu scaled by 0.5 to the thesis's mean group size of 11 (scripts/ch6/group_size.py; R)
                  Variant("Exp. 4, state grouping, lambda 0.8", {"lam": 0.8, "grouping": True, "mu_low": 0.25,
                                                                 "mu_high": 1.25}),
                  # the thesis's stated mu ~ U(0.5, 2.5) (6.6.4), beside our halved one
                  Variant(STATED_GROUPING, {"lam": 0.8, "grouping": True, "mu_low": 0.5, "mu_high": 2.5})),
        quantities=(*QUANTITIES, GROUPING), x_label="trials", y_label="reinforcement per primitive step (greedy tests)",
        description="the persistence rule of Exp. 3 with 5x the reward delay: timeout 1000, reward 500, gamma 0.998; "
                    "thesis: without grouping it fails from room B, with grouping it is comparable to Exp. 3"),
    ExperimentSpec(
        name="recharge-together", title="Exp. 5: behaviours pre-trained only 300 steps, then learned alongside the "
        "high level", section="6.6.5 Fig. 6.6", run="connrl.experiments.recharge:run_recharge",
        params=override(RechargeParams(), {"pretrain_steps": 300}, "experiment recharge-together"),
        profiles=PROFILES, variants=(Variant("Exp. 5: behaviours learned alongside", {}),),
        quantities=(*QUANTITIES, *(Quantity(f"pretrain_trials_{t}", f"{t}'s trials of its 300 pre-training steps",
                                            section="6.6.5") for t in ("DK", "DP", "WFL", "WFR")),
                    Quantity("pretrain_steps", "primitive steps of the four behaviours' pre-training", section="6.7")),
        x_label="trials", y_label="reinforcement per primitive step (greedy tests)",
        description="Exp. 3's learner over fresh behaviours (10/10/5/5 taught lessons, about 300 primitive steps "
                    "each), which go on learning from their own reinforcement; thesis: little progress for 50 "
                    "trials, then slightly below Exp. 3, docking from every room by the end"),
    ExperimentSpec(
        name="recharge-own-library", title="Exp. 3 over behaviours each run trains within the thesis's budget "
        "(8.5: 7,000 steps in all)", section="6.6.3, 6.7, 8.5", run="connrl.experiments.recharge:run_own_library",
        params=override(OwnLibraryParams(), {"paths": 1}, "experiment recharge-own-library"),
        profiles={**PROFILES, "tiny": {**PROFILES["tiny"], "library_steps": 140}},
        variants=(Variant("Exp. 3, own behaviours within 7,000 steps", {}),),
        quantities=(*QUANTITIES, *OWN_LIBRARY), x_label="trials",
        y_label="reinforcement per primitive step (greedy tests)",
        description="Exp. 3 (persistence rule) over a library each run trains first, from scratch, as the shipped one "
                    "was but within 8.5's steps (DK 2,000, DP 2,000, WFL 1,500, WFR 1,500), then frozen; 6.7's "
                    "equal-cost comparison with Exp. 1 (about 40,000 steps each, behaviours included)"),
]

# Issue 42's re-check of Ch. 6's high-level choices (picked on development seeds 100-119 by room B docked at trial 60,
# the claim itself): Exp. 3 again on seeds never used before (docs/notes/prereg-fresh-checks.md)
FRESH_SEED = 4000
EXPERIMENTS.append(replace(
    EXPERIMENTS[0], name="recharge-behaviours-fresh", seed=FRESH_SEED,
    title=f"Exp. 3: recharging over learned behaviours, fresh seeds {FRESH_SEED}-{FRESH_SEED + 6}",
    variants=tuple(v for v in EXPERIMENTS[0].variants if v.label == "Exp. 3: persistence rule")))
