"""Ch. 6, Experiment 1 (6.6.1, Fig. 6.5): learning to recharge without the hierarchy.

One monolithic QCON-T learns Q(state, action) over the six primitive actions on the flat input (every elementary
input and the 16 high-level ones, ``connrl.envs.robot.recharge``), with 10 taught lessons of the scripted recharging
teacher and "the same learning technique used to train the elementary behaviors" (Ch. 5: stuck detection, P_l 0.02,
taught lessons replayed after every trial), 30 hidden units, gamma 0.99, lambda 0.8, 300 trials of at most 200
steps. No collision penalty (6.6.1; ``collision_penalty`` tries the thesis's -5 / -10). The protocol and the test
tasks are Exps 2-3's (``connrl.experiments.recharge.run_rooms``: fixed tasks per start room, tested every 10 trials).
"""

from __future__ import annotations

import numpy as np

from connrl.experiments.recharge import PROFILES, QUANTITIES, run_rooms
from connrl.experiments.spec import ExperimentSpec, RunResult, Variant, override
from connrl.tasks.recharge import CHG_TAUGHT, FlatParams, make_flat_agent, make_flat_env  # noqa: F401


def run_flat(p: FlatParams, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    result, agent = run_rooms(p, rng, make_flat_env, make_flat_agent, progress)
    return result


CHAPTER = 6  # the thesis chapter of these experiments (`connrl reproduce --chapters`)
EXPERIMENTS = [
    ExperimentSpec(
        name="recharge-flat", title="Exp. 1: recharging without the hierarchy (monolithic QCON-T, flat input)",
        section="6.6.1 Fig. 6.5", run="connrl.experiments.recharge_flat:run_flat",
        params=override(FlatParams(), {"paths": 1}, "experiment recharge-flat"),
        profiles={**PROFILES, "quick": {"runs": 2, "trials": 100, "tests_per_room": 5}},
        variants=(Variant("Exp. 1: no hierarchy", {}),),
        quantities=QUANTITIES,
        x_label="trials", y_label="reinforcement per primitive step (greedy tests)",
        description="10 taught lessons of the scripted recharging teacher; thesis: after 300 trials generally unable "
                    "to recharge from rooms B and C, colliding on more than 5 % of steps"),
]
