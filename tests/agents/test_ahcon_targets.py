"""AHCON's on-line step at the end of an episode (Fig. 3.2 steps 4-6): a time limit (truncated) is not a failure, so
the critic's target still bootstraps, r + gamma V(y); only a terminal step (terminated) has V(y) taken as 0. The
policy net then learns from the same target's error, target - V(x) read before the critic's update.

Each test computes the target by hand from V(y) and V(x) read before the step and compares the agent's nets with
twin nets (same seed) given that target and error through the nets' own ``update`` and ``update_error``: the
agent's target logic is what is tested (issue 46: AHCON's time-limit rule had no exact test)."""

import numpy as np
import pytest

from connrl.agents import AHCON, AHCONConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.nets import NetConfig

GAMMA, R = 0.9, 0.3
X, Y = np.array([0.5, -0.5, 0.2, 0.1]), np.array([0.1, 0.2, -0.3, 0.4])


def ahcon(seed=0):
    cfg = AHCONConfig(v_net=NetConfig(4, 5, lr=0.3, init_range=0.5), policy_net=NetConfig(4, 5, lr=0.3, init_range=0.5),
                      temperature=TemperatureSchedule.inverse(10, 30, 50), gamma=GAMMA)
    return AHCON(cfg, 2, np.random.default_rng(seed))


def one_step(terminated, truncated):
    """The agent's and the twin's V(x) and policy merits after one on-line step ending the episode, and the target."""
    agent, twin = ahcon(), ahcon()
    agent.begin_trial(X)
    a = agent.act(X)
    v_y, v_x = float(agent.v.value(Y, 0)), float(agent.v.value(X, 0))  # before the update (Fig. 3.2 step 4)
    target = R + (0.0 if terminated else GAMMA * v_y)
    agent.observe(a, R, Y, terminated, truncated)
    assert twin.v.update(X, 0, target) == v_x  # the twin's critic starts where the agent's did
    twin.policy.update_error(X, a, target - v_x)
    return (agent.v.value(X, 0), agent.policy.values(X)), (twin.v.value(X, 0), twin.policy.values(X)), target


def test_a_truncated_step_bootstraps_the_critic_and_the_policy_from_the_next_state():
    (v, merits), (want_v, want_merits), target = one_step(terminated=False, truncated=True)
    assert target != pytest.approx(R)  # the bootstrap term is not negligible, so V(y) = 0 would show
    assert v == want_v
    np.testing.assert_array_equal(merits, want_merits)


def test_a_terminated_step_has_no_future():
    (v, merits), (want_v, want_merits), target = one_step(terminated=True, truncated=False)
    assert target == R
    assert v == want_v
    np.testing.assert_array_equal(merits, want_merits)


def test_the_two_ends_differ():
    """The rule is visible: the same step truncated and terminated leaves different nets."""
    truncated, _, _ = one_step(terminated=False, truncated=True)
    terminated, _, _ = one_step(terminated=True, truncated=False)
    assert truncated[0] != terminated[0]
