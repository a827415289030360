"""5.5's claim on noise: "the robot's performance in the noisy world was almost the same as that in a noise-free
world". DP, DK and WFL learned exactly as in Exp. 1 with the most taught lessons (10, 10, 5; ``robot-teaching-*``),
in the noisy world of 5.2.1 (the Ch. 5 default: ~8 % control error, +-10 % sonar error and one sonar reading in 96
set to 127) and with both kinds of noise off in training and tests. The simulator draws the same random numbers
either way (connrl.envs.robot), so a noise-free run differs from its noisy twin only by the noise.

"Almost the same" is read as: the final performances are the same within +-10 % of the noisy world's mean by two
one-sided t-tests (TOST) at 0.05 (R; the thesis gives no margin): ``connrl.report.verdicts.compare``, the rule the
whole results page uses; a difference is a Welch t-test, and otherwise the runs decide neither.
"""

from __future__ import annotations

from connrl.experiments.robot import PROFILES, Q_FINAL, Q_MEAN, RobotParams
from connrl.experiments.spec import ExperimentSpec, Variant

TASK_LESSONS = (("DP", 10), ("DK", 10), ("WFL", 5))  # Exp. 1's most-taught variants (5.4.1)
THESIS = "the robot's performance in the noisy world was almost the same as that in a noise-free world"  # 5.5

CHAPTER = 5  # the thesis chapter of these experiments (`connrl reproduce --chapters`)
EXPERIMENTS = [ExperimentSpec(
    name="robot-noise", title="DP, DK and WFL learned with and without sensing and control noise", section="5.5",
    run="connrl.experiments.robot:run_robot", params=RobotParams(),
    profiles={k: {key: v for key, v in over.items() if key != "paths"} for k, over in PROFILES.items()},
    variants=tuple(Variant(f"{task}, {'noisy' if noise else 'noise-free'}", {"task": task, "lessons": n,
                                                                            "noise": noise})
                   for task, n in TASK_LESSONS for noise in (True, False)),
    quantities=(Q_FINAL, Q_MEAN), x_label="trials", y_label="reinforcement per step (greedy test, 50 tasks)",
    description=f"the thesis (5.5): '{THESIS}'")]

