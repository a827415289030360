"""AHCON (Fig. 3.2), the adaptive heuristic critic with a V-net and a policy net, and AHCON-R/-T (3.5, 3.7)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.agents.base import LessonAgent, ReplayConfig
from connrl.core.exploration import StuckConfig, TemperatureSchedule, boltzmann_select
from connrl.core.lessons import Lesson
from connrl.core.replay import replay_ahc
from connrl.nets import OAON, NetConfig


@dataclass(frozen=True)
class AHCONConfig:
    """AHCON and its options; ``replay=None`` gives plain AHCON."""

    v_net: NetConfig  # evaluation network V(x) (3.3)
    policy_net: NetConfig  # policy network, one per action, outputs action merits (3.3)
    temperature: TemperatureSchedule  # Boltzmann temperature over trials on the merits (Eq. 3.4)
    gamma: float = 0.9  # discount factor (4.2.7)
    lam: float = 0.0  # TD(lambda) recency factor for replay (5.1)
    online: bool = True  # learn from each step as it happens (Fig. 3.2 steps 5-6)
    replay: ReplayConfig | None = None  # experience replay (3.5); Ch. 4 uses P_t = 0.2 for AHC agents
    target_clip: float | None = None  # truncate V targets above this value (4.2.4: 1)
    stuck: StuckConfig | None = None  # raise T when stuck (4.2.6)

    def __post_init__(self):
        if not 0 <= self.gamma <= 1:
            raise ValueError(f"gamma must be in [0, 1], got {self.gamma}")
        if not 0 <= self.lam <= 1:
            raise ValueError(f"lam must be in [0, 1], got {self.lam}")
        if self.v_net.n_inputs != self.policy_net.n_inputs:
            raise ValueError("v_net and policy_net must have the same number of inputs")


class AHCON(LessonAgent):
    """Adaptive heuristic critic (Fig. 3.2) with optional backward replay (Fig. 5.1b) and teaching."""

    def __init__(self, config: AHCONConfig, n_actions: int, rng: np.random.Generator, policy=None, planner=None):
        super().__init__(config, n_actions, rng, stuck=config.stuck)
        self.v = OAON(config.v_net, 1, rng)
        # any object with values/update_error works as the policy net (Ch. 4's rotated global net, 4.2.4)
        self.policy = policy if policy is not None else OAON(config.policy_net, n_actions, rng)
        # relaxation planning with an action model (AHCON-M, 3.6.1): connrl.core.planning.RelaxationPlanner
        self.planner = planner

    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = True) -> None:
        super().begin_trial(obs, info, trial=trial, learning=learning)
        if self.planner is not None:
            self.planner.begin_trial()

    def act(self, obs, info=None, *, greedy: bool = False) -> int:
        if not self.learning or self._x is None:
            # test trials never call observe(), so the input must come from obs, not the cached _x
            self._x = self.encode(obs)
        x = self._x
        t = self.temperature(info, greedy)
        merits = self.policy.values(x)
        if self.planner is not None and self.learning and not greedy and self.planner.plan(self, x, merits, t):
            merits = self.policy.values(x)  # plan before choosing (3.6.1)
        a, self.last_probabilities = boltzmann_select(merits, t, self.rng)
        return a

    def observe(self, action, reward, next_obs, terminated, truncated, info=None) -> None:
        x, y = self._x, self.encode(next_obs)
        if self.config.online:
            target = self.online_target(reward, 0.0 if terminated else self.v.value(y, 0))  # Fig. 3.2 step 4
            e = self.v.update(x, 0, target)  # step 5
            self.policy.update_error(x, action, target - e)  # step 6
        if self.planner is not None:
            self.planner.observe(x, action, reward, y, terminated)  # a learned model trains on-line (4.2.5)
        self.book.recorder.add(x, action, reward, y)
        self.book.ended = (bool(terminated), bool(truncated))
        self._x = y

    def replay_lesson(self, lesson: Lesson, p_threshold: float) -> None:
        replay_ahc(self.v, self.policy, lesson, self.replay_params(p_threshold))

