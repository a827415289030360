"""Information tests of the reconstructed DP task: what copying the taught lessons, and the scripted teacher itself,
score on the 50 test tasks of a Ch. 5 run (not thesis figures; docs/RECONSTRUCTION.md, "Calibration of door passing").

``robot-dp-copy`` copies a run's taught lessons onto its fresh Q-nets by supervised learning
(``connrl.agents.cloning``): the taught action's net towards +50, the others towards -50, with the run's learning
rate and momentum, until the greedy action is the taught one on every taught state or ``copy_epochs`` run out,
testing the greedy policy as ``connrl run robot-teaching-dp`` does. Same seeds, same test tasks as the RL run of
the same seed. The thesis's 10-lesson robot scores 2.5 reinforcement/step after 10 trials (5.6); a reconstruction
in which a copy of those 10 lessons stays far below that cannot reproduce it from the lessons alone (a reference,
not a strict bound: QCON-T also learns from its own trials). Copies of 100 demonstrations ask
whether the 52 inputs carry what door passing needs at all; the teacher, which reads the true pose, is the top.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.agents.cloning import agreement, copy_epoch, lesson_pairs
from connrl.experiments.robot import RobotParams, RobotRun
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant, override, param
from connrl.tasks.robot import evaluate, teacher_score

CHECKPOINTS = (0, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)


@dataclass(frozen=True)
class CopyParams(RobotParams):
    """A Ch. 5 run's world, nets and test tasks (``RobotParams``), with the copying done instead of learning."""

    policy: str = param("copy", note="'copy': the nets copy the taught lessons; 'teacher': the scripted teacher drives",
                        choices=("copy", "teacher"))
    copy_epochs: int = param(200, ">=0", "passes over the taught states at most (stops early at full agreement)")

    def __post_init__(self):
        super().__post_init__()  # check_types(self) included

    def check_combination(self):
        super().check_combination()
        if self.policy == "copy" and self.lessons == 0:
            raise ValueError("parameter lessons must be >= 1 when policy is 'copy' (there is nothing to copy)")


def _passes(run: RobotRun) -> tuple[float, int]:
    paths: list = [None] * len(run.tests)
    perf = evaluate(run.test_env, run.agent, run.tests, run.test_seeds, run.p.max_steps, paths)
    return perf, sum(bool(p["success"]) for p in paths)


def run_copy(p: CopyParams, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    run = RobotRun(p, rng)
    if p.policy == "teacher":
        perf, passes = teacher_score(run.test_env, run.tests, run.test_seeds)
        return RunResult([0], [perf], {"performance": perf, "passes": passes}, [{"epochs": 0, "performance": perf,
                                                                                   "passes": passes}])
    states, actions = lesson_pairs(run.agent.book.taught)
    nets, margin = run.agent.q, 0.5 * p.value_range
    xs, ys, rows, full = [], [], [], None
    marks = [e for e in CHECKPOINTS if e < p.copy_epochs] + [p.copy_epochs]
    for epoch in range(p.copy_epochs + 1):
        agree = agreement(nets, states, actions)
        if full is None and agree == 1.0:
            full = epoch
        if epoch in marks or full == epoch:
            perf, passes = _passes(run)
            xs.append(epoch)
            ys.append(perf)
            rows.append({"epochs": epoch, "performance": perf, "passes": passes, "agreement": agree})
            progress(epoch, p.copy_epochs)
        if full is not None or epoch == p.copy_epochs:
            break
        copy_epoch(nets, states, actions, margin, run.agent.rng)
    last = rows[-1]
    for epoch in (e for e in marks if e > xs[-1]):  # a finished copy no longer changes: same curve length every run
        xs.append(epoch)
        ys.append(last["performance"])
    return RunResult(xs, ys, {"performance": last["performance"], "passes": last["passes"],
                              "agreement": last["agreement"], "epochs_to_copy": full}, rows)


Q_PERF = Quantity("performance", "test reinforcement/step of the copy (or the teacher) at the end", "higher",
                  "5.4; R")
Q_PASSES = Quantity("passes", "test tasks of 50 in which the door is passed", "higher", "5.4; R")
Q_AGREE = Quantity("agreement", "share of taught states whose greedy action is the taught one", "higher", "3.7")

PROFILES = {"tiny": {"runs": 1, "test_tasks": 3, "copy_epochs": 2}, "quick": {"runs": 2, "test_tasks": 25},
            "full": {"runs": 7}}

CHAPTER = 5  # the thesis chapter of these experiments (`connrl reproduce --chapters`)
EXPERIMENTS = [
    ExperimentSpec(
        name="robot-dp-copy", title="The copy bound: DP policies copied from the taught lessons, and the teacher "
        "(not a thesis figure)", section="5.4.1, 5.6; R", run="connrl.experiments.robot_bounds:run_copy",
        params=override(CopyParams(), {"task": "DP"}, "experiment robot-dp-copy"), profiles=PROFILES,
        variants=(Variant("copy 3 lessons", {"lessons": 3}), Variant("copy 10 lessons", {"lessons": 10}),
                  Variant("copy 100 demonstrations", {"lessons": 100}),
                  Variant("scripted teacher", {"policy": "teacher", "lessons": 0})),
        quantities=(Q_PERF, Q_PASSES, Q_AGREE), x_label="copying epochs",
        y_label="reinforcement per step (greedy test, 50 tasks)", y_reference={"2.5": 2.5, "5": 5.0},
        description="supervised copies of the taught lessons on the RL run's nets, tested on its 50 test tasks; "
                    "the thesis's 10-lesson robot reaches 2.5 after 10 trials"),
]
