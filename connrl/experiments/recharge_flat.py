"""Ch. 6, Experiment 1 (6.6.1, Fig. 6.5): learning to recharge without the hierarchy.

One monolithic QCON-T learns Q(state, action) over the six primitive actions on the flat input (every elementary
input and the 16 high-level ones, ``connrl.envs.robot.recharge``), with 10 taught lessons of the scripted recharging
teacher and "the same learning technique used to train the elementary behaviors" (Ch. 5: stuck detection, P_l 0.02,
taught lessons replayed after every trial), 30 hidden units, gamma 0.99, lambda 0.8, 300 trials of at most 200
steps. No collision penalty (6.6.1; ``collision_penalty`` tries the thesis's -5 / -10). The protocol and the test
tasks are Exps 2-3's (``connrl.experiments.recharge.run_rooms``: fixed tasks per start room, tested every 10 trials).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.experiments.recharge import PROFILES, QUANTITIES, run_rooms
from connrl.experiments.spec import ExperimentSpec, RunResult, Variant, check_types, override, param
from connrl.tasks.recharge import CHG_TAUGHT, make_flat_agent, make_flat_env


@dataclass(frozen=True)
class FlatParams:
    """One Experiment 1 run: 6.6.1's values, else Ch. 5's (5.3)."""

    lessons: int = param(CHG_TAUGHT, ">=0", "taught lessons (6.6.1: 10)")
    hidden: int = param(30, ">=1", "(6.6.1)")
    lr: float = param(0.05, ">0", "(6.6: fixed to 0.05)")
    momentum: float = param(0.9, "0..<1", "(Ch. 5)")
    init_range: float = param(0.5, ">0", "(Ch. 5)")
    gamma: float = param(0.99, "0..1", "(6.6.1)")
    lam: float = param(0.8, "0..1", "(6.6.1)")
    t_start: float = param(0.05, ">0", "(6.6)")
    t_end: float = param(0.02, ">0")
    capacity: int = param(100, ">=1", "(App. A.2, Ch. 5)")
    lessons_per_trial: int = param(60, ">=0", "(6.6)")
    p_threshold: float = param(0.02, "0..<1", "P_l (Ch. 5)")
    online: bool = param(True, note="(Ch. 5)")
    stuck_window: int = param(8, ">=1", "stuck detection (Ch. 5's)")
    stuck_radius: float = param(12.0, ">=0")
    stuck_boost: float = param(5.0, ">0")
    collision_penalty: float = param(0.0, note="(6.6.1: none; -5 and -10 also tried)")
    trials: int = param(300, ">=1", "(Fig. 6.5)")
    max_steps: int = param(200, ">=1", "(6.6)")
    test_every: int = param(10, ">=1")
    tests_per_room: int = param(10, ">=1", "as Exps 2-3")
    paths: int = param(0, ">=0", "greedy solution paths recorded per start room after the last trial")

    def __post_init__(self):
        check_types(self)
        if not self.collision_penalty <= 0:
            raise ValueError(f"parameter collision_penalty must be <= 0, got {self.collision_penalty}")
        if self.lessons > CHG_TAUGHT:
            raise ValueError(f"parameter lessons must be at most {CHG_TAUGHT} (the shipped recharging lessons), got "
                             f"{self.lessons}")


def run_flat(p: FlatParams, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    result, agent = run_rooms(p, rng, make_flat_env, make_flat_agent, progress)
    return result


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
