"""QCON's on-line target at the end of an episode (Fig. 3.4 step 4): a time limit (truncated) is not a failure, so the
target still bootstraps, r + gamma max_a Q(y, a); only a terminal step (terminated) has u = 0.

Each test computes the target by hand from Q(y) read before the step and compares the agent's net with a twin net
(same seed) given that target through the Q-function's own ``update``: the agent's target logic is what is tested."""

import numpy as np
import pytest

from connrl.agents import QCON, QCONConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.nets import NetConfig

GAMMA, R = 0.9, 0.3
X, Y = np.array([0.5, -0.5, 0.2, 0.1]), np.array([0.1, 0.2, -0.3, 0.4])


def qcon(seed=0):
    cfg = QCONConfig(net=NetConfig(4, 5, lr=0.2, init_range=0.5), temperature=TemperatureSchedule.inverse(10, 30, 50),
                     gamma=GAMMA)
    return QCON(cfg, 2, np.random.default_rng(seed))


def one_step(terminated, truncated):
    """Returns the agent's and the twin's Q(x) after one on-line step ending the episode, and the hand target."""
    agent, twin = qcon(), qcon()
    agent.begin_trial(X)
    a = agent.act(X)
    q_y = agent.q.values(Y)  # before the update, as Fig. 3.4 step 4 reads it
    target = R + (0.0 if terminated else GAMMA * max(float(v) for v in q_y))
    agent.observe(a, R, Y, terminated, truncated)
    twin.q.update(X, a, target)
    return agent.q.values(X), twin.q.values(X), target


def test_truncated_step_bootstraps_from_the_next_state():
    got, expected, target = one_step(terminated=False, truncated=True)
    assert target != pytest.approx(R)  # the bootstrap term is not negligible, so u = 0 would show
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def test_terminated_step_has_no_future():
    got, expected, target = one_step(terminated=True, truncated=False)
    assert target == R
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
