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


def test_ahcon_online_steps_give_the_exact_weights_of_fig_3_2():
    """Two on-line steps (the second terminal) against an independent NumPy net: target = r + gamma V(y) (0 after a
    terminal step), V moved toward it, the taken action's merit moved by the error target - V(x) (momentum 0.9
    carries the first step into the second)."""
    from tests.numpy_nets import NumpyOAON

    cfg = AHCONConfig(v_net=NetConfig(3, 4, value_range=1.5, init_range=0.5, lr=0.3, momentum=0.9),
                      policy_net=NetConfig(3, 4, init_range=0.5, lr=0.2, momentum=0.9), temperature=TEMP, gamma=0.8)
    agent = AHCON(cfg, 2, np.random.default_rng(3))
    v, pol = NumpyOAON(agent.v), NumpyOAON(agent.policy)
    xs = [np.array([0.5, -0.5, 0.2]), np.array([0.1, 0.2, -0.3]), np.array([-0.4, 0.3, 0.6])]
    agent.begin_trial(xs[0])
    for k, (r, done) in enumerate([(0.3, False), (-1.0, True)]):
        a = agent.act(xs[k])
        target = r + (0.0 if done else cfg.gamma * v.value(xs[k + 1], 0))
        v_x = v.update(xs[k], 0, target)
        pol.update_error(xs[k], a, target - v_x)
        agent.observe(a, r, xs[k + 1], done, False)
        v.assert_same(agent.v)
        pol.assert_same(agent.policy)
