"""One builder for the thesis's two memoryless learners, shared by the thesis's wiring (``connrl.tasks``) and the
own-task API (``connrl.own.api``): QCON (Fig. 3.4) or AHCON (Fig. 3.2) on one net configuration."""

from __future__ import annotations

import numpy as np

from connrl.agents.ahcon import AHCON, AHCONConfig
from connrl.agents.base import ReplayConfig
from connrl.agents.qcon import QCON, QCONConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.nets import NetConfig


def make_learner(ahc: bool, net: NetConfig, n_actions: int, rng: np.random.Generator, *,
                 temperature: TemperatureSchedule, gamma: float, lam: float, replay: ReplayConfig | None,
                 online: bool = True) -> QCON | AHCON:
    """QCON with one Q-net per action on ``net``, or AHCON whose critic and policy nets both take ``net``: the
    merits on V's scale, since Fig. 3.2 moves them by V's TD error. ``replay`` None: no experience replay (QCON,
    AHCON); a ``ReplayConfig``: QCON-R / AHCON-R (and -T with taught lessons)."""
    if ahc:
        return AHCON(AHCONConfig(v_net=net, policy_net=net, temperature=temperature, gamma=gamma, lam=lam,
                                 online=online, replay=replay), n_actions, rng)
    return QCON(QCONConfig(net=net, temperature=temperature, gamma=gamma, lam=lam, online=online, replay=replay),
                n_actions, rng)
