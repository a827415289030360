"""Pole balancing wiring (App. C, 7.5.4): the cart-pole worlds and the memoryless QCON / AHCON agents of pole-full.

The builders take ``PoleParams``, declared here beside them (``make_envs`` also the hidden-state pole's
``connrl.tasks.hidden_state.PoleHiddenParams``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.agents import LinearSchedule, ReplayConfig
from connrl.agents.build import make_learner
from connrl.core.exploration import TemperatureSchedule
from connrl.core.params import check_types, param
from connrl.core.rollout import run_trial
from connrl.envs.pole import TEST_START_ANGLES_DEG, PoleBalancingEnv
from connrl.nets import NetConfig
from connrl.tasks.hidden_state import PoleHiddenParams


@dataclass(frozen=True)
class PoleParams:
    """Table B.1, Task 4 (the memoryless full-state agent reuses the window-Q column with N = 1), plus the
    choices where the thesis is silent (R; docs/RECONSTRUCTION.md, "Pole balancing" and "Learners and
    protocols"); see docs/RESULTS.md for how they were chosen."""

    agent: str = param("qcon", note="'qcon' or 'ahcon'", choices=("qcon", "ahcon"))
    observe: str = param("full", note="full state (x, x_dot, theta, theta_dot)", choices=("full", "x_theta"))
    hidden: int = param(6, ">=0", "H_q (Table B.1)")
    lr: float = param(0.25, ">0", "eta_q (Table B.1)")
    init_range: float = param(0.5, ">0", "App. B")
    momentum: float = param(0.9, "0..<1", "App. B")
    gamma: float = param(0.9, "0..1", "App. B")
    lam: float = param(0.7, "0..1", "Table B.1")
    inv_t_start: float = param(20.0, ">0", "1/T: 20 -> 50 (Table B.1)")
    inv_t_end: float = param(50.0, ">0")
    anneal_trials: int = param(1000, ">=1", "trials over which 1/T moves (R)")
    capacity: int = param(70, ">=1", "replay only the latest 70 trials (7.5)")
    lessons_per_trial: int = param(70, ">=0", "lessons replayed after each trial, drawn by App. A.2 from the latest "
                                   "70 (R)")
    p_threshold: float = param(1e-4, "0..<1", "P_l for the latest lesson (App. B)")
    p_threshold_oldest: float | None = param(1e-7, ">0", "P_l for the oldest lesson (App. B)")
    online: bool = param(True, note="also learn on-line from each step (Fig. 3.4)")
    train_max_steps: int = param(2000, ">=1", "training trials are cut here (truncated, bootstrapped) (R)")
    start_x: float = param(1.2, ">=0", "training start ranges (R)")
    start_theta: float = param(0.06, ">=0")
    test_steps: int = param(5001, ">=1", "'balanced for over 5000 steps' (7.5.4)")
    max_trials: int = param(1000, ">=1", "7.5.4: 'not always found within 1000 trials'")

    def __post_init__(self):
        check_types(self)


def make_envs(p: PoleParams | PoleHiddenParams, observe: str) -> tuple[PoleBalancingEnv, PoleBalancingEnv]:
    """The training world (cut at ``train_max_steps``, random starts) and the test world (7.5.4)."""
    train_env = PoleBalancingEnv(observe=observe, max_steps=p.train_max_steps, start_x=p.start_x,
                                 start_theta=p.start_theta)
    return train_env, PoleBalancingEnv(observe=observe, max_steps=p.test_steps)


def make_agent(p: PoleParams, n_inputs: int, rng: np.random.Generator):
    """QCON-R or AHCON-R with Table B.1's Task 4 parameters (N = 1)."""
    net = NetConfig(n_inputs, p.hidden, value_range=1.0, init_range=p.init_range, lr=p.lr,
                    momentum=p.momentum if p.hidden > 0 else 0.0)
    temp = TemperatureSchedule.inverse(p.inv_t_start, p.inv_t_end, p.anneal_trials)
    replay = ReplayConfig(capacity=p.capacity, lessons_per_trial=LinearSchedule(p.lessons_per_trial,
                                                                                p.lessons_per_trial),
                          p_threshold=p.p_threshold, p_threshold_oldest=p.p_threshold_oldest)
    if p.agent in ("qcon", "ahcon"):
        return make_learner(p.agent == "ahcon", net, 2, rng, temperature=temp, gamma=p.gamma, lam=p.lam,
                            replay=replay, online=p.online)
    raise ValueError(f"agent must be 'qcon' or 'ahcon', got {p.agent!r}")


def satisfactory(env: PoleBalancingEnv, agent, test_steps: int) -> bool:
    """7.5.4: balanced for more than 5000 steps from each of the 7 test starts (stops at the first failure)."""
    for deg in TEST_START_ANGLES_DEG:
        stats = run_trial(env, agent, trial=0, learning=False, options={"theta_deg": deg}, max_steps=test_steps)
        if stats.terminated:
            return False
    return True
