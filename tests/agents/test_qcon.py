"""QCON: the on-line update of Fig. 3.4, terminal steps and clipped targets (4.2.4)."""

import numpy as np

from connrl.agents import QCON, QCONConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.nets import NetConfig

TEMP = TemperatureSchedule.inverse(10, 30, 50)


def qcon(n_inputs=4, n_actions=2, replay=None, seed=0, **kw):
    cfg = QCONConfig(net=NetConfig(n_inputs, 5, lr=0.2, init_range=0.5), temperature=TEMP, replay=replay, **kw)
    return QCON(cfg, n_actions, np.random.default_rng(seed))


def test_qcon_online_update_is_fig_3_4():
    agent = qcon(online=True)
    x, y = np.array([0.5, -0.5, 0.2, 0.1]), np.array([0.1, 0.2, -0.3, 0.4])
    agent.begin_trial(x)
    a = agent.act(x)
    q_before = agent.q.values(x)
    expected = 0.3 + 0.9 * agent.q.values(y).max()  # u' = r + gamma max_k Q(y, k)
    twin = qcon(online=True)
    twin.q.update(x, a, expected)
    agent.observe(a, 0.3, y, False, False)
    np.testing.assert_allclose(agent.q.values(x), twin.q.values(x))
    assert agent.q.values(x)[1 - a] == q_before[1 - a]


def test_terminal_step_has_no_future_and_targets_are_clipped():
    agent = qcon(target_clip=1.0)
    twin = qcon(target_clip=1.0)
    x, y = np.ones(4) * 0.5, -np.ones(4) * 0.5
    agent.begin_trial(x)
    a = agent.act(x)
    agent.observe(a, 3.0, y, True, False)
    twin.q.update(x, a, 1.0)  # r = 3 -> clipped to 1, no bootstrap
    np.testing.assert_allclose(agent.q.values(x), twin.q.values(x))
