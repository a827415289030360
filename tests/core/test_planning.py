"""Relaxation planning (Figs. 3.5, 3.6) and the planner's rules (3.6.1, 4.2.5)."""

import numpy as np
import pytest

from connrl.core.planning import PlanningConfig, RelaxationPlanner, relaxation_ahc, relaxation_q
from connrl.nets import NetConfig


class TableQ:
    """A Q-function with fixed values per input (keyed by x[0]) that records updates."""

    def __init__(self, table):
        self.table, self.updates, self.n_actions = table, [], 4

    def values(self, x):
        return np.array(self.table[float(x[0])], dtype=float)

    def value(self, x, a):
        return float(self.values(x)[a])

    def update(self, x, a, target):
        self.updates.append((float(x[0]), a, target))
        return 0.0

    def update_error(self, x, a, err):
        self.updates.append((float(x[0]), a, err))
        return 0.0


def test_relaxation_q_is_fig_3_6():
    q = TableQ({1.0: [0.2, 0.5, -0.1, 0.0], 2.0: [0.9, 0.95, 0.1, 0.3]})
    x = np.array([0.0])
    outcomes = [(np.array([1.0]), 0.0, False), (np.array([2.0]), 0.4, False), (np.array([2.0]), -1.0, True)]
    targets = relaxation_q(q, x, [0, 1, 3], outcomes, gamma=0.9, clip=1.0)
    # U'_a = r + gamma max_k Q(y, k): 0.9*0.5; 0.4 + 0.9*0.95 = 1.255 -> truncated to 1 (4.2.4); terminal: -1
    np.testing.assert_allclose(targets, [0.45, 1.0, -1.0])
    assert q.updates == [(0.0, 0, pytest.approx(0.45)), (0.0, 1, 1.0), (0.0, 3, -1.0)]


def test_relaxation_ahc_is_fig_3_5():
    v = TableQ({0.0: [0.1], 1.0: [0.5], 2.0: [-0.2]})
    policy = TableQ({})
    x = np.array([0.0])
    p = np.array([0.5, 0.3, 0.19, 0.01])
    outcomes = [(np.array([1.0]), 0.0, False), (np.array([2.0]), 0.4, False), (np.array([1.0]), -1.0, True)]
    e, mu = relaxation_ahc(v, policy, x, p, [0, 1, 2], outcomes, gamma=0.9, clip=1.0)
    np.testing.assert_allclose(e, [0.45, 0.4 - 0.18, -1.0])  # E_a = r + gamma V(y), 0 after death
    assert mu == pytest.approx(np.dot([0.5, 0.3, 0.19], e) / 0.99)  # renormalised over S
    assert v.updates == [(0.0, 0, pytest.approx(0.45))]  # V(x) toward max_a E_a (step 6)
    assert [u[1] for u in policy.updates] == [0, 1, 2]  # merits by E_a - mu (step 7)
    np.testing.assert_allclose([u[2] for u in policy.updates], e - mu)


class CountingModel:
    def __init__(self):
        self.calls = []

    def simulate(self, x, actions):
        self.calls.append(list(actions))
        return [(x, 0.0, True) for _ in actions]


class FakeAgent:
    def __init__(self, trial):
        from connrl.agents import QCONConfig
        from connrl.core.exploration import TemperatureSchedule

        self.trial = trial
        self.q = TableQ({0.0: [0, 0, 0, 0]})
        self.config = QCONConfig(net=NetConfig(1, 1), temperature=TemperatureSchedule.inverse(1, 1, 1),
                                 target_clip=1.0)


def test_planner_plans_only_promising_actions_and_counts_them():
    model = CountingModel()
    planner = RelaxationPlanner(model, PlanningConfig(promising=0.02, start_trial=10))
    x = np.zeros(1)
    assert not planner.plan(FakeAgent(trial=9), x, np.zeros(4), 0.1)  # learned model: none before play 10
    assert planner.plan(FakeAgent(trial=10), x, np.array([0.0, 0.0, -1.0, 0.0]), 0.1)
    assert model.calls == [[0, 1, 3]]  # P(2) = e^-10 / ... < 2%: not promising
    assert not planner.plan(FakeAgent(trial=10), x, np.array([1.0, 0.0, 0.0, 0.0]), 0.1)  # one promising
    assert not planner.plan(FakeAgent(trial=10), x, np.zeros(4), 0.0)  # T = 0 (a test): never plans
    assert (planner.hypothetical, planner.steps) == (3, 4)
    planner.begin_trial()
    assert (planner.hypothetical, planner.steps) == (0, 0)
