"""QCON (Fig. 3.4) and its replay / teaching extensions: QCON-R (3.5) and QCON-T (3.7).

The Q-function is any object with ``values(x)`` and ``update(x, a, target)`` (``connrl.core.replay.QFunction``);
by default one network per action (OAON, 3.4). Ch. 4's "global" agents pass a single rotated net instead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.agents.base import LessonAgent, ReplayConfig
from connrl.core.exploration import StuckConfig, TemperatureSchedule, boltzmann_select
from connrl.core.grouping import group_lesson
from connrl.core.lessons import Lesson
from connrl.core.replay import QFunction, replay_q, replay_q_lessons
from connrl.nets import OAON, NetConfig


@dataclass(frozen=True)
class QCONConfig:
    """QCON and its options; ``replay=None`` gives plain QCON, with replay QCON-R, with taught lessons QCON-T."""

    net: NetConfig  # the Q-nets, one per action (3.4)
    temperature: TemperatureSchedule  # Boltzmann temperature over trials (3.4, Table 4.1, 5.3.4)
    gamma: float = 0.9  # discount factor (4.2.7, 5.3.3, App. B)
    lam: float = 0.0  # TD(lambda) recency factor for replay (5.1; Ch. 4 uses 0)
    online: bool = True  # learn from each step as it happens (Fig. 3.4 step 5)
    replay: ReplayConfig | None = None  # experience replay after each trial (3.5); None = plain QCON
    target_clip: float | None = None  # truncate Q targets above this value (4.2.4: 1)
    stuck: StuckConfig | None = None  # raise T when stuck (4.2.6, 5.3.4)

    def __post_init__(self):
        if not 0 <= self.gamma <= 1:
            raise ValueError(f"gamma must be in [0, 1], got {self.gamma}")
        if not 0 <= self.lam <= 1:
            raise ValueError(f"lam must be in [0, 1], got {self.lam}")


class QCON(LessonAgent):
    """Connectionist Q-learning (Fig. 3.4), optionally with backward TD(lambda) replay and teaching."""

    def __init__(self, config: QCONConfig, n_actions: int, rng: np.random.Generator,
                 q: QFunction | None = None, planner=None, *, merit_scale: float = 1.0):
        super().__init__(config, n_actions, rng, stuck=config.stuck, merit_scale=merit_scale)
        self.q = q if q is not None else OAON(config.net, n_actions, rng)
        # relaxation planning with an action model (QCON-M, 3.6.2): connrl.core.planning.RelaxationPlanner
        self.planner = planner
        self.grouped_steps = self.groups = 0  # state grouping's tally: mean group size = grouped_steps / groups

    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = True) -> None:
        super().begin_trial(obs, info, trial=trial, learning=learning)
        if self.planner is not None:
            self.planner.begin_trial()

    def act(self, obs, info=None, *, greedy: bool = False) -> int:
        if not self.learning or self._x is None:
            # test trials never call observe(), so the input must come from obs, not the cached _x
            self._x = self.encode(obs)
        x = self._x
        q = self.q.values(x)
        t = self.temperature(info, greedy)
        if self.planner is not None and self.learning and not greedy and self.planner.plan(self, x, q, t):
            q = self.q.values(x)  # plan before choosing (3.6.1), so the choice benefits from the look-ahead
        a, self.last_probabilities = boltzmann_select(q, t, self.rng)
        return a

    def observe(self, action, reward, next_obs, terminated, truncated, info=None) -> None:
        x, y = self._x, self.encode(next_obs)
        if self.config.online:  # Fig. 3.4 steps 4-5
            self.q.update(x, action, self.online_target(reward, 0.0 if terminated else self.next_value(y, info)))
        if self.planner is not None:
            self.planner.observe(x, action, reward, y, terminated)  # a learned model trains on-line (4.2.5)
        self.book.recorder.add(x, action, reward, y)
        self.book.ended = (bool(terminated), bool(truncated))
        self._x = y

    def next_value(self, y: np.ndarray, info: dict | None) -> float:
        """The on-line target's max_a Q(y, a) (Fig. 3.4 step 4); a subclass may restrict the actions it ranges over."""
        return float(self.q.values(y).max())

    def replays_in_one_call(self) -> bool:
        r = self.config.replay  # state grouping draws from the generator; batch mode is not compiled
        return (r is not None and r.grouping is None and not self._replay.batch and type(self.q) is OAON
                and super().replays_in_one_call())

    def replay_in_one_call(self, lessons: list[Lesson], thresholds: list[float], params) -> None:
        replay_q_lessons(self.q, lessons, thresholds, params, self.lesson_options)

    def replay_lesson(self, lesson: Lesson, p_threshold: float, weights=None, allowed=None) -> None:
        """Replay one lesson (Fig. 5.1), over its groups of similar states when ``replay.grouping`` is set (6.6.4);
        ``weights`` / ``allowed`` as ``connrl.core.replay.replay_q``'s."""
        params, grouping = self.replay_params(p_threshold), self.config.replay.grouping
        if grouping is None:
            replay_q(self.q, lesson, params, weights=weights, allowed=allowed)
            return
        g = group_lesson(lesson, self.config.gamma, grouping, self.rng, weights, allowed)
        self.grouped_steps += len(lesson)
        self.groups += len(g.lesson)
        replay_q(self.q, g.lesson, params, weights=g.weights, allowed=g.allowed, discounts=g.discounts)

    one_call_reproduces = (replay_lesson,)  # replay_lessons' one call does its work
