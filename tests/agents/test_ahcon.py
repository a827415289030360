"""AHCON: the on-line update of Fig. 3.2."""

import numpy as np

from connrl.agents import AHCON, AHCONConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.nets import NetConfig

TEMP = TemperatureSchedule.inverse(10, 30, 50)


def test_ahcon_online_update_is_fig_3_2():
    cfg = AHCONConfig(v_net=NetConfig(4, 3, lr=0.3), policy_net=NetConfig(4, 3, lr=0.3), temperature=TEMP)
    agent = AHCON(cfg, 2, np.random.default_rng(0))
    x, y = np.array([0.5, -0.5, 0.2, 0.1]), np.array([0.1, 0.2, -0.3, 0.4])
    agent.begin_trial(x)
    a = agent.act(x)
    e, ep = agent.v.value(x, 0), 0.2 + 0.9 * agent.v.value(y, 0)
    merit = agent.policy.value(x, a)
    agent.observe(a, 0.2, y, False, False)
    assert (agent.v.value(x, 0) - e) * (ep - e) > 0  # V moved toward e'
    assert (agent.policy.value(x, a) - merit) * (ep - e) > 0  # merit of a moved with the TD error
