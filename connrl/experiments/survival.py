"""Chapter 4: the eight frameworks on the survival task (Figs. 4.3-4.5, the tables of 4.3.4, 4.4 and 4.5).

Protocol (4.3.1): each run draws 300 training and 50 test environments (food layouts) from its seed; the
agent plays the 300 training environments in order, learning; before the first play and after every 20
it plays the 50 test environments with learning off and T = 0; the curve is the mean food per test play.
A thesis study is 7 runs per agent.

Experiments (``connrl run NAME``):

* ``survival-study1`` — Fig. 4.3: all agents, global action representation, Table 4.1 parameters;
* ``survival-study2`` — Fig. 4.4: all agents, local representation, learning rates doubled (4.3.3);
* ``survival-planning`` — Fig. 4.5: hypothetical actions per step of the -M agents of Study 2;
* ``survival-speedup`` — the table of 4.5: plays until the Study 2 Q-agents reach 8 food per play;
* ``survival-eval`` — 4.3.4: QCON-T (global) after 300 plays, tested on 8000 random environments.

The -M agents come with both models of 4.2.5 ("learned" and "perfect"), as 4.4.3 compares both.

Per-run quantities: ``final_food`` (mean food per test play over the last three tests, plays 260-300, our
measure of "final performance"), ``food_auc`` (mean over all 16 tests, our measure of "learning speed"),
``plays_to_8`` (first test at which the run reaches 8 food per play). The speedup table of 4.5 is read off
the *mean* curve of the runs, as the thesis's learning curves are means over its 7 experiments.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from connrl.envs.survival.world import REWARD_FOOD
from connrl.experiments.protocol import train_and_test
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant, check_types, param
from connrl.tasks.survival import (
    FRAMEWORKS,
    MODELS,
    FoodReward,
    SurvivalAgentParams,
    SurvivalEnv,
    environment_sets,
    evaluate,
    make_survival_agent,
)
from connrl.tasks.survival import test_plays as _test_plays
from connrl.tasks.survival_models import probe_experiences
from connrl.tasks.survival_train import learning_play

# the learned model's yardstick (4.4.3): fixed experiences, the same for every run of a representation (not
# parameters: they are measurement, and leave the runs and their folders as they were)
PROBE_SEED, PROBE_SIZE, PROBE_EVERY = 4403, 1000, 5
FRESH_SEED = 2000  # first seed of the fresh-seed runs: Ch. 4 development used 0-6, 11-12 and 100-102


@dataclass(frozen=True)
class SurvivalParams:
    """One Ch. 4 run (4.3.1); the agents' own constants are ``connrl.tasks.survival.SurvivalAgentParams``."""

    framework: str = param("QCON", note="one of connrl.tasks.survival.FRAMEWORKS", choices=FRAMEWORKS)
    model: str = param("learned", note="action model of the -M agents (4.2.5)", choices=MODELS)
    representation: str = param("global", note="4.2.3", choices=("global", "local"))
    lr_scale: float = param(1.0, ">0", "Study 2: 2.0 (4.3.3)")
    train_plays: int = param(300, ">=1", "4.3.1")
    test_envs: int = param(50, ">=1", "4.3.1")
    test_every: int = param(20, ">=0", "4.3.1")
    eval_envs: int = param(0, ">=0", "4.3.4: 8000 after training (survival-eval only)")
    curve: str = param("food", note="'food' (Figs. 4.3/4.4) or 'planning' (Fig. 4.5: hypothetical actions per step)",
                       choices=("food", "planning"))
    planning_block: int = param(10, ">=1", "plays averaged per point of the planning curve")
    p_threshold: float | None = param(None, "0..<1", "P_t: actions less likely are not replayed (3.5.1); None: "
                                      "4.2.7's per framework")
    food_reward: float = param(REWARD_FOOD, ">=0", "the reinforcement for food in training (4.2.1); tests count food")

    def __post_init__(self):
        check_types(self)

    def check_combination(self):
        if self.food_reward != REWARD_FOOD and self.framework.endswith(("-M", "-T")):
            raise ValueError(f"parameter food_reward applies to agents without a model or taught lessons (theirs "
                             f"hold the world's {REWARD_FOOD}), got framework {self.framework}")


def _agent_params(p: SurvivalParams) -> SurvivalAgentParams:
    return SurvivalAgentParams(framework=p.framework, representation=p.representation, model=p.model,
                               lr_scale=p.lr_scale, plays=p.train_plays if p.train_plays > 1 else 2,
                               p_threshold=p.p_threshold)


def _training_env(p: SurvivalParams):
    env = SurvivalEnv(p.representation)
    return FoodReward(env, p.food_reward) if p.food_reward != REWARD_FOOD else env


def run_survival(p: SurvivalParams, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    """One run of the 4.3.1 protocol for one agent (and, with ``eval_envs``, the 4.3.4 evaluation)."""
    train, test = environment_sets(int(rng.integers(2**31 - 1)), p.train_plays, p.test_envs)
    env = _training_env(p)
    env.reset(seed=int(rng.integers(2**31 - 1)))
    test_env = SurvivalEnv(p.representation)
    agent = make_survival_agent(_agent_params(p), env.unwrapped, rng)
    planner = getattr(agent, "planner", None)
    # a learned model's accuracy on fixed experiences (4.4.3), from their own seed: the run's values stay as they were
    probes = (probe_experiences(p.representation, PROBE_SEED, PROBE_SIZE)
              if hasattr(getattr(planner, "model", None), "probe_errors") else None)
    n_tests = (p.train_plays // p.test_every + 1) if p.test_every else 0
    total = p.train_plays + n_tests * p.test_envs + p.eval_envs
    done, rows, xs, ys, hyp = 0, [], [], [], []

    def do_test(plays):
        nonlocal done
        r = _test_plays(test_env, agent, test)
        xs.append(plays)
        ys.append(r["food"])
        rows.append({"kind": "test", "plays": plays, "food": r["food"], "all_food": r["all_food"],
                     "killed": r["killed"], "starved": r["starved"]})
        done += len(test)
        progress(done, total)

    def do_train(k):
        nonlocal done
        stats = learning_play(env, agent, trial=k, options={"layout_seed": train[k]})
        row = {"kind": "train", "plays": k + 1, "food": stats.info["food_eaten"], "outcome": stats.info["outcome"],
               "steps": stats.steps, "stuck_steps": agent.explore.boosted}
        if planner is not None:
            h = planner.hypothetical / max(planner.steps, 1)
            hyp.append(h)
            row["hypothetical_per_step"] = h
            if hasattr(planner.model, "pop_errors"):
                row.update({f"model_{k2}": v for k2, v in planner.model.pop_errors().items()})
            if probes is not None and (k == 0 or (k + 1) % PROBE_EVERY == 0):
                row.update({f"model_{k2}": v for k2, v in planner.model.probe_errors(probes).items()})
        rows.append(row)
        done += 1
        progress(done, total)
        return stats

    train_and_test(len(train), do_train, do_test, test_every=p.test_every, test_first=bool(n_tests),
                   test_last=False, agent=agent)
    metrics, extra = _metrics(xs, ys, hyp)
    if p.eval_envs:
        ev = evaluate(agent, p.representation, int(rng.integers(2**31 - 1)), p.eval_envs,
                      lambda d: progress(done + d, total))
        metrics.update({k: ev[k] for k in ("eval_food", "eval_all_food_pct", "eval_killed_pct",
                                           "eval_starved_pct")})
        extra["eval_histogram_pct"] = ev["histogram_pct"]
        extra["example_play"] = ev["example_play"]
    progress(total, total)
    if p.curve == "planning":
        b = p.planning_block
        cx = [float(i + b) for i in range(0, len(hyp), b)]
        cy = [float(np.mean(hyp[i:i + b])) for i in range(0, len(hyp), b)]
        return RunResult(cx, cy, metrics, rows, extra)
    return RunResult(xs, ys, metrics, rows, extra)


def _metrics(xs, ys, hyp) -> tuple[dict, dict]:
    """Per-run quantities of the learning curve (see the module docstring) and of the planning effort."""
    metrics: dict = {}
    if ys:
        metrics["final_food"] = float(np.mean(ys[-3:]))
        metrics["food_auc"] = float(np.mean(ys))
        reached = [x for x, y in zip(xs, ys, strict=True) if y >= 8.0]
        metrics["plays_to_8"] = float(reached[0]) if reached else None
    extra: dict = {"test_plays": xs, "test_food": ys}
    if hyp:
        metrics["hypothetical_per_step_first20"] = float(np.mean(hyp[:20]))
        metrics["hypothetical_per_step_last20"] = float(np.mean(hyp[-20:]))
        extra["hypothetical_per_step"] = hyp
    return metrics, extra


def _variants(study: int, q_only: bool = False) -> tuple[Variant, ...]:
    out = []
    for base in ("QCON",) if q_only else ("AHCON", "QCON"):
        for ext in ("", "-R", "-M learned", "-M perfect", "-T"):
            fw, _, model = (base + ext).partition(" ")
            label = f"{fw} ({model} model)" if model else fw
            params = {"framework": fw} | ({"model": model} if model else {})
            out.append(Variant(label, params, _THESIS_PLAYS_TO_8.get(label, {}) if study == 2 else {}))
    return tuple(out)


_THESIS_PLAYS_TO_8 = {  # 4.5 table (Study 2, Q-agents): plays to reach 8 food per play
    "QCON": {"plays_to_8": 200}, "QCON-M (learned model)": {"plays_to_8": 140},
    "QCON-M (perfect model)": {"plays_to_8": 95}, "QCON-R": {"plays_to_8": 80}, "QCON-T": {"plays_to_8": 60},
}

_CURVE_QUANTITIES = (
    Quantity("final_food", "mean food per test play, last 3 tests (plays 260-300)", "higher", "4.3"),
    Quantity("food_auc", "mean food per test play over all tests (learning speed)", "higher", "4.4"),
    Quantity("plays_to_8", "first test at which a run reaches 8 food per play", "lower", "4.5"),
)
_PROFILES = {
    "tiny": {"runs": 1, "train_plays": 4, "test_envs": 2, "test_every": 2},
    "quick": {"runs": 2, "train_plays": 100, "test_envs": 20},
    "full": {"runs": 7},
}
_STUDY2 = replace(SurvivalParams(), representation="local", lr_scale=2.0)

_TUNING = [("AHCON-R", pt) for pt in (0.05, 0.1, 0.2, 0.4)] + [("QCON-R", pt) for pt in (0.0, 0.001, 0.01, 0.1)]

_STUDIES = (
    ExperimentSpec(
        name="survival-study1", title="Survival, Study 1: global action representation (Fig. 4.3)",
        section="4.3.2", run="connrl.experiments.survival:run_survival", params=SurvivalParams(),
        profiles=_PROFILES, variants=_variants(1), quantities=_CURVE_QUANTITIES,
        x_label="plays", y_label="food per test play"),
    ExperimentSpec(
        name="survival-study2", title="Survival, Study 2: local action representation (Fig. 4.4)",
        section="4.3.3", run="connrl.experiments.survival:run_survival", params=_STUDY2,
        profiles=_PROFILES, variants=_variants(2), quantities=_CURVE_QUANTITIES,
        x_label="plays", y_label="food per test play", y_reference={"8 food (4.5 table)": 8.0}),
)

CHAPTER = 4  # the thesis chapter of these experiments (`connrl reproduce --chapters`)
EXPERIMENTS = [
    *_STUDIES,
    *(replace(study, name=f"{study.name}-fresh", title=f"Survival, Study {k} on fresh seeds {FRESH_SEED}-"
              f"{FRESH_SEED + 6}", section=section, seed=FRESH_SEED)  # issue 31's check: the same runs, new seeds
      for k, study, section in ((1, _STUDIES[0], "4.3.2, 4.4"), (2, _STUDIES[1], "4.3.3, 4.4, 4.5"))),
    ExperimentSpec(
        name="survival-planning", title="Hypothetical actions per step, Study 2 -M agents (Fig. 4.5)",
        section="4.4.3", run="connrl.experiments.survival:run_survival",
        params=replace(_STUDY2, curve="planning"), profiles=_PROFILES,
        variants=tuple(v for v in _variants(2) if "-M" in v.label),
        quantities=(Quantity("hypothetical_per_step_first20", "hypothetical actions per step, plays 1-20",
                             "higher", "4.4.3"),
                    Quantity("hypothetical_per_step_last20", "hypothetical actions per step, last 20 plays",
                             "lower", "4.4.3")),
        x_label="plays", y_label="hypothetical actions per step", y_reference={"maximum (4 actions)": 4.0}),
    ExperimentSpec(
        name="survival-speedup", title="Study 2 Q-agents: plays to reach 8 food per play (4.5 table)",
        section="4.5", run="connrl.experiments.survival:run_survival", params=_STUDY2, profiles=_PROFILES,
        variants=_variants(2, q_only=True), quantities=_CURVE_QUANTITIES,
        x_label="plays", y_label="food per test play", y_reference={"8 food": 8.0}),
    ExperimentSpec(
        name="survival-eval", title="QCON-T after 300 plays on 8000 random environments (4.3.4)",
        section="4.3.4", run="connrl.experiments.survival:run_survival",
        params=SurvivalParams(framework="QCON-T", test_every=0, eval_envs=8000),
        profiles={"tiny": {"runs": 1, "train_plays": 3, "eval_envs": 3},
                  "quick": {"runs": 1, "eval_envs": 1000}, "full": {"runs": 7}},
        variants=(Variant("QCON-T", {}, {"eval_food": 12.1, "eval_all_food_pct": 39.9, "eval_killed_pct": 31.9,
                                         "eval_starved_pct": 28.2}),),
        quantities=(Quantity("eval_food", "food per play", "higher", "4.3.4"),
                    Quantity("eval_all_food_pct", "% of plays with all 15 pieces", "higher", "4.3.4"),
                    Quantity("eval_killed_pct", "% of plays killed by an enemy", "lower", "4.3.4"),
                    Quantity("eval_starved_pct", "% of plays that ran out of energy", "lower", "4.3.4")),
        x_label="plays", y_label="food per play"),
    ExperimentSpec(  # 4.2.7: "For AHCON-R, P_t = 0.2 ... roughly the best"; QCON-R similar at 0.1-0.001, poor at 0
        name="survival-tuning", title="Survival, Study 1: AHCON-R and QCON-R with replay thresholds P_t around "
        "4.2.7's", section="4.2.7", run="connrl.experiments.survival:run_survival", params=SurvivalParams(),
        profiles=_PROFILES, variants=tuple(Variant(f"{fw} P_t={pt:g}", {"framework": fw, "p_threshold": pt})
                                           for fw, pt in _TUNING),
        quantities=_CURVE_QUANTITIES[:2], x_label="plays", y_label="food per test play"),
    ExperimentSpec(  # 4.2.1: "a few different values were tried for Agent AHCON, and 0.4 gave roughly the best"
        name="survival-food", title="Survival, Study 1: AHCON with food rewards around 4.2.1's 0.4", section="4.2.1",
        run="connrl.experiments.survival:run_survival", params=SurvivalParams(framework="AHCON"),
        profiles=_PROFILES, variants=tuple(Variant(f"food reward {r:g}", {"food_reward": r})
                                           for r in (0.1, 0.2, 0.4, 0.8)),
        quantities=_CURVE_QUANTITIES[:2], x_label="plays", y_label="food per test play"),
]
