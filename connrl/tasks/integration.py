"""Ch. 8 wiring: the behaviour-level recharging task without X-Y (8.1), in the original or the changed layout (8.4),
and its two high-level learners -- Ch. 6 Experiment 3's memoryless Q-nets on 14 inputs (8.2) and recurrent Q-nets
over behaviours (8.3, ``connrl.agents.behaviour_level.BehaviourRecurrentQ``). ``p`` is a Ch. 8 parameter set
(``connrl.experiments.integration.IntegrationParams``); the protocols below state what each builder reads."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from connrl.agents import LinearSchedule, ReplayConfig
from connrl.agents.behaviour_level import BehaviourChoice, BehaviourRecurrentQ
from connrl.agents.memory import RecurrentQConfig
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, HIGH_SIZE, HIGH_SIZE_NO_XY
from connrl.nets.recurrent import RecurrentNetConfig
from connrl.tasks.recharge import (
    BehaviourEnv,
    BehaviourTaskParams,
    HighLevelAgentParams,
    LearnerParams,
    _shipped_library,
    cooling,
    make_high_level_agent,
)


class XYParams(Protocol):
    """What ``n_inputs`` reads (read-only, as the frozen parameter dataclasses are)."""

    @property
    def xy(self) -> bool: ...  # the 2 X-Y inputs (Ch. 6) or none (Ch. 8)


class IntegrationWorldParams(BehaviourTaskParams, XYParams, Protocol):
    """What ``make_integration_env`` reads."""


class RecurrentAgentParams(LearnerParams, XYParams, Protocol):
    """What ``make_recurrent_agent`` reads."""

    @property
    def context(self) -> int: ...
    @property
    def success_reward(self) -> float: ...
    @property
    def share_output(self) -> bool: ...
    @property
    def p_oldest(self) -> float: ...
    @property
    def output_init(self) -> float: ...
    @property
    def cool_trials(self) -> int: ...
    @property
    def replay_from_start(self) -> bool: ...
    @property
    def persistence(self) -> bool: ...
    @property
    def target_max(self) -> str: ...


class IntegrationAgentParams(HighLevelAgentParams, RecurrentAgentParams, Protocol):
    """What ``make_integration_agent`` reads: either learner's parameters, and which one."""

    @property
    def memory(self) -> str: ...  # "none" (8.2) or "recurrent" (8.3)


def n_inputs(p: XYParams) -> int:
    return HIGH_SIZE if p.xy else HIGH_SIZE_NO_XY


def make_integration_env(p: IntegrationWorldParams, layout: str = "default") -> BehaviourEnv:
    return BehaviourEnv(_shipped_library(), max_steps=p.max_steps, step_scale=p.step_scale,
                        success_reward=p.success_reward, xy=p.xy, layout=layout, xy_scale=p.xy_scale)


def make_recurrent_agent(p: RecurrentAgentParams, rng: np.random.Generator) -> BehaviourRecurrentQ:
    """Experiment 2's learner (8.3): Ch. 6's choice over behaviours with recurrent Q-nets and batch replay."""
    net = RecurrentNetConfig(n_inputs(p), p.hidden, p.context, value_range=p.success_reward, init_range=p.init_range,
                             lr=p.lr, momentum=p.momentum, share_output=p.share_output, output_init=p.output_init)
    replay = ReplayConfig(capacity=p.capacity, lessons_per_trial=LinearSchedule(p.lessons_per_trial,
                                                                                p.lessons_per_trial),
                          p_threshold=0.0, p_threshold_oldest=p.p_oldest, batch=True)
    cfg = RecurrentQConfig(net=net, temperature=cooling(p), gamma=p.gamma, lam=p.lam, replay=replay)
    agent = BehaviourRecurrentQ(cfg, len(BEHAVIOUR_TASKS), rng, BehaviourChoice(persistence=p.persistence,
                                                                                target_max=p.target_max),
                                merit_scale=p.success_reward)
    agent.replay_at_most_stored = not p.replay_from_start  # as Ch. 6's learner (RechargeParams.replay_from_start)
    return agent


def make_integration_agent(p: IntegrationAgentParams, rng: np.random.Generator):
    """Experiment 1's memoryless or Experiment 2's recurrent learner, as ``p.memory`` says."""
    if p.memory == "recurrent":
        return make_recurrent_agent(p, rng)
    return make_high_level_agent(p, rng, n_inputs=n_inputs(p))
