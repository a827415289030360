"""Pole balancing wiring (App. C, 7.5.4): the cart-pole worlds and the memoryless QCON / AHCON agents of pole-full.

Builders take the experiment's parameters by attribute; the protocols below state what each reads (satisfied by
``connrl.experiments.pole.PoleParams``, and ``PoleWorldParams`` also by
``connrl.experiments.hidden_state.PoleHiddenParams``).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from connrl.agents import AHCON, QCON, AHCONConfig, LinearSchedule, QCONConfig, ReplayConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.core.rollout import run_trial
from connrl.envs.pole import TEST_START_ANGLES_DEG, PoleBalancingEnv
from connrl.nets import NetConfig


class PoleWorldParams(Protocol):
    """What ``make_envs`` reads (read-only, as the frozen parameter dataclasses are)."""

    @property
    def train_max_steps(self) -> int: ...
    @property
    def start_x(self) -> float: ...
    @property
    def start_theta(self) -> float: ...
    @property
    def test_steps(self) -> int: ...


class PoleAgentParams(Protocol):
    """What ``make_agent`` reads."""

    @property
    def agent(self) -> str: ...
    @property
    def hidden(self) -> int: ...
    @property
    def init_range(self) -> float: ...
    @property
    def lr(self) -> float: ...
    @property
    def momentum(self) -> float: ...
    @property
    def inv_t_start(self) -> float: ...
    @property
    def inv_t_end(self) -> float: ...
    @property
    def anneal_trials(self) -> int: ...
    @property
    def capacity(self) -> int: ...
    @property
    def lessons_per_trial(self) -> int: ...
    @property
    def p_threshold(self) -> float: ...
    @property
    def p_threshold_oldest(self) -> float | None: ...
    @property
    def gamma(self) -> float: ...
    @property
    def lam(self) -> float: ...
    @property
    def online(self) -> bool: ...


def make_envs(p: PoleWorldParams, observe: str) -> tuple[PoleBalancingEnv, PoleBalancingEnv]:
    """The training world (cut at ``train_max_steps``, random starts) and the test world (7.5.4)."""
    train_env = PoleBalancingEnv(observe=observe, max_steps=p.train_max_steps, start_x=p.start_x,
                                 start_theta=p.start_theta)
    return train_env, PoleBalancingEnv(observe=observe, max_steps=p.test_steps)


def make_agent(p: PoleAgentParams, n_inputs: int, rng: np.random.Generator):
    """QCON-R or AHCON-R with Table B.1's Task 4 parameters (N = 1)."""
    net = NetConfig(n_inputs, p.hidden, value_range=1.0, init_range=p.init_range, lr=p.lr,
                    momentum=p.momentum if p.hidden > 0 else 0.0)
    temp = TemperatureSchedule.inverse(p.inv_t_start, p.inv_t_end, p.anneal_trials)
    replay = ReplayConfig(capacity=p.capacity, lessons_per_trial=LinearSchedule(p.lessons_per_trial,
                                                                                p.lessons_per_trial),
                          p_threshold=p.p_threshold, p_threshold_oldest=p.p_threshold_oldest)
    if p.agent == "qcon":
        return QCON(QCONConfig(net=net, temperature=temp, gamma=p.gamma, lam=p.lam, online=p.online,
                               replay=replay), 2, rng)
    if p.agent == "ahcon":
        return AHCON(AHCONConfig(v_net=net, policy_net=net, temperature=temp, gamma=p.gamma, lam=p.lam,
                                 online=p.online, replay=replay), 2, rng)
    raise ValueError(f"agent must be 'qcon' or 'ahcon', got {p.agent!r}")


def satisfactory(env: PoleBalancingEnv, agent, test_steps: int) -> bool:
    """7.5.4: balanced for more than 5000 steps from each of the 7 test starts (stops at the first failure)."""
    for deg in TEST_START_ANGLES_DEG:
        stats = run_trial(env, agent, trial=0, learning=False, options={"theta_deg": deg}, max_steps=test_steps)
        if stats.terminated:
            return False
    return True
