"""Ch. 8 wiring: the behaviour-level recharging task without X-Y (8.1), in the original or the changed layout (8.4),
and its two high-level learners -- Ch. 6 Experiment 3's memoryless Q-nets on 14 inputs (8.2) and recurrent Q-nets
over behaviours (8.3, ``connrl.agents.behaviour_level.BehaviourRecurrentQ``). ``p`` is a Ch. 8 parameter set,
``IntegrationParams``, declared here beside the builders."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.agents import LinearSchedule, ReplayConfig
from connrl.agents.behaviour_level import BehaviourChoice, BehaviourRecurrentQ
from connrl.agents.memory import RecurrentQConfig
from connrl.core.params import param
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, HIGH_SIZE, HIGH_SIZE_NO_XY
from connrl.nets.recurrent import RecurrentNetConfig
from connrl.tasks.recharge import (
    BehaviourEnv,
    RechargeParams,
    _shipped_library,
    cooling,
    make_high_level_agent,
)

MEMORY = ("none", "recurrent")

@dataclass(frozen=True)
class IntegrationParams(RechargeParams):
    """One Ch. 8 run: Ch. 6 Experiment 3's parameters (``RechargeParams``) without X-Y, and the memory used."""

    xy: bool = param(False, note="the 2 X-Y inputs (Ch. 6) or none (Ch. 8, 8.1)")
    memory: str = param("none", note="'none': Exp. 1's memoryless Q-nets (8.2); 'recurrent': Exp. 2's recurrent-Q "
                        "(8.3)", choices=MEMORY)
    context: int = param(8, ">=0", "context units of the recurrent Q-nets (8.3); memory='none' has none")
    share_output: bool = param(False, note="the recurrent nets share their hidden->output connections (7.4: 'tends to "
                               "help')")
    final_tests_per_room: int = param(20, ">=1", "Exp. 3: fresh tasks per start room in each layout after the last "
                                      "trial (R)")
    probe_samples: int = param(300, ">=0", "at most this many near-door steps kept per run for the hidden-state probe "
                               "(R)")

    def __post_init__(self):
        super().__post_init__()  # check_types(self) included
        if self.memory == "recurrent" and self.context > self.hidden:
            raise ValueError(f"parameter context must be at most hidden ({self.hidden}): context units copy hidden "
                             f"units (7.4), got {self.context}")
        if self.pretrain_steps or (self.grouping and self.memory == "recurrent"):
            raise ValueError("parameters pretrain_steps (Ch. 6 Exp. 5) and grouping with memory='recurrent' are not "
                             "built for Ch. 8: use pretrain_steps=0, and grouping only with memory='none'")
        if self.memory == "recurrent" and self.online:
            raise ValueError("parameter online must be False with memory='recurrent': the recurrent nets learn only by "
                             "batch replay (7.5, 8.3)")
        if self.memory == "none" and self.share_output:
            raise ValueError("parameter share_output applies to memory='recurrent' only")


def n_inputs(p: IntegrationParams) -> int:
    return HIGH_SIZE if p.xy else HIGH_SIZE_NO_XY


def make_integration_env(p: IntegrationParams, layout: str = "default") -> BehaviourEnv:
    return BehaviourEnv(_shipped_library(), max_steps=p.max_steps, step_scale=p.step_scale,
                        success_reward=p.success_reward, xy=p.xy, layout=layout, xy_scale=p.xy_scale)


def make_recurrent_agent(p: IntegrationParams, rng: np.random.Generator) -> BehaviourRecurrentQ:
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


def make_integration_agent(p: IntegrationParams, rng: np.random.Generator):
    """Experiment 1's memoryless or Experiment 2's recurrent learner, as ``p.memory`` says."""
    if p.memory == "recurrent":
        return make_recurrent_agent(p, rng)
    return make_high_level_agent(p, rng, n_inputs=n_inputs(p))
