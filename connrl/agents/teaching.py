"""QCON-T for the robot tasks of Ch. 5: fast backward TD(lambda) replay and the *lower* / *raise* repairs (5.4.3).

``TeachingQCON`` is QCON (Fig. 3.4) with experience replay (Fig. 5.1a) and teaching (3.7), plus three things
Ch. 5 needs:

- **Repairs (5.4.3).** Each time a taught lesson is replayed, the agent checks, for every taught experience
  ``(x, a1)``, the condition ``Q(x, a1) >= Q(x, a_i)`` for all ``i`` (Eq. 5.6). On a violation the *lower*
  repair back-propagates ``Q(x, a1) - Q(x, a_i)`` through net ``a_i`` (every violating ``a_i``); the *raise*
  repair back-propagates ``Q(x, a_max) - Q(x, a1)`` through net ``a1``, where ``a_max`` is the most
  over-valued other action. The check is made right after the TD update of that experience (the thesis does
  not say when within the replay; we do it in the same backward pass, with the net as it is then).
- **Temperature on the +-1 scale.** The Boltzmann selector sees ``Q / merit_scale`` (Q / 100 for the robot):
  with Q in +-100 (5.3.1) a temperature of 0.05 (5.3.4) only makes sense relative to +-1, the range Ch. 4
  uses with similar temperatures (Table 4.1). The non-policy test of replay (P_l = 2 %, 5.3.5) uses the same
  probabilities.
- **Speed.** ``connrl.core.replay.replay_q`` replays a whole lesson into an OAON by its registered Numba
  kernel (the same loop as ``replay_q_reference``, repairs included); ``fast=False`` forces the plain loop.

"Fewer lessons were replayed in the beginning when there were not many lessons available" (5.3.5 fn. 1):
``learn`` replays ``min(lessons_per_trial, lessons in memory)`` experienced lessons.

Values marked (R) are reconstructions; docs/RECONSTRUCTION.md, "Learners and protocols", gives each with its reason.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.agents.qcon import QCON, QCONConfig
from connrl.core.lessons import Lesson
from connrl.core.replay import REPAIRS, replay_q

# ------------------------------------------------------------------------------------------- the agent


@dataclass(frozen=True)
class TeachingConfig:
    """What ``TeachingQCON`` adds to QCONConfig (5.3.4, 5.4.3)."""

    repair: str = "none"  # "none" | "lower" | "raise" repairs on taught lessons (5.4.3)
    merit_scale: float = 100.0  # Boltzmann sees Q / merit_scale: Q in +-100 (5.3.1), T on the +-1 scale (R)
    fast: bool = True  # use the Numba lesson kernel when the Q-function is an OAON

    def __post_init__(self):
        if self.repair not in REPAIRS:
            raise ValueError(f"repair must be one of {REPAIRS}, got {self.repair!r}")
        if not self.merit_scale > 0:
            raise ValueError(f"merit_scale must be > 0, got {self.merit_scale}")


class TeachingQCON(QCON):
    """QCON-T of Ch. 5 with the 5.4.3 repairs; see the module docstring."""

    replay_at_most_stored = True  # 5.3.5 fn. 1

    def __init__(self, config: QCONConfig, n_actions: int, rng: np.random.Generator,
                 teaching: TeachingConfig | None = None, q=None):
        self.teaching = teaching or TeachingConfig()
        super().__init__(config, n_actions, rng, q=q, merit_scale=self.teaching.merit_scale)

    def replays_in_one_call(self) -> bool:  # experienced lessons take no repairs: QCON's one call, when compiled
        return self.teaching.fast and super().replays_in_one_call()

    def replay_lesson(self, lesson: Lesson, p_threshold: float) -> None:
        params = self.replay_params(p_threshold)
        repair = self.teaching.repair if lesson.taught else "none"
        replay_q(self.q, lesson, params, repair, fast=self.teaching.fast)

    one_call_reproduces = (replay_lesson,)  # for experienced lessons, which take no repairs
