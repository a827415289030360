"""Relaxation planning (Figs. 3.5, 3.6), the planner's rules (3.6.1, 4.2.5), the survival action models,
and the rotated single net of the global representation (4.2.4)."""

import numpy as np
import pytest

from connrl.core.planning import PlanningConfig, RelaxationPlanner, relaxation_ahc, relaxation_q
from connrl.envs.survival import ACTION_ROTATION, ROTATION_PERMUTATIONS, SurvivalEnv, rotate_observation
from connrl.nets import OAON, NetConfig
from connrl.nets.rotated import RotatedNet
from connrl.tasks.survival_models import LearnedSurvivalModel, PerfectSurvivalModel

PERMS = np.stack([ROTATION_PERMUTATIONS[ACTION_ROTATION[a]] for a in range(4)])


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


def test_perfect_model_steps_a_copy_and_leaves_the_live_play_alone():
    env = SurvivalEnv("global")
    x, _ = env.reset(seed=3, options={"food": [(17, 12), (18, 13)]})
    before = env.get_state(include_rng=True)
    model = PerfectSurvivalModel(env, np.random.default_rng(0))
    outs = model.simulate(x, [0, 1, 3])
    after = env.get_state(include_rng=True)
    assert after["agent"] == before["agent"] and after["rng"] == before["rng"]
    # enemies start 12+ cells away, so every simulated observation is the real one for that move
    for a, (y, r, terminal) in zip([0, 1, 3], outs, strict=True):
        twin = SurvivalEnv("global")
        twin.reset(seed=3, options={"food": [(17, 12), (18, 13)]})
        y_true, r_true, term_true, _, _ = twin.step(a)
        np.testing.assert_array_equal(y, y_true)
        assert (r, terminal) == (r_true, term_true)
    assert [o[1] for o in outs] == [0.4, 0.4, 0.0]


@pytest.mark.parametrize("rep", ["global", "local"])
def test_learned_model_learns_reward_and_enemy_units(rep):
    env = SurvivalEnv(rep)
    x, _ = env.reset(seed=1)
    model = LearnedSurvivalModel(env, np.random.default_rng(0))
    y = x.copy()
    y[52:84] = -0.5
    y[52 + 5] = 0.5  # an enemy sensor turns on after the move
    for _ in range(150):
        model.learn(x, 2, -1.0, y, True)
    r, enemy = model.predict(x, 2)
    assert r < -0.6
    np.testing.assert_array_equal(enemy, y[52:84])
    (y_sim, r_sim, terminal), = model.simulate(x, [2])
    assert terminal and r_sim == pytest.approx(r)  # predicted death ends the simulated play
    np.testing.assert_array_equal(y_sim[52:84], y[52:84])
    if rep == "global":  # the units the model does not learn come from the simulator (4.2.5)
        np.testing.assert_array_equal(np.delete(y_sim, np.s_[52:84]), np.delete(env.step(2)[0], np.s_[52:84]))


def test_learned_model_global_nets_are_shared_by_rotation():
    env = SurvivalEnv("global")
    x, _ = env.reset(seed=2)
    model = LearnedSurvivalModel(env, np.random.default_rng(1))
    rng = np.random.default_rng(5)
    for _ in range(30):  # random training so the enemy net is not trivial
        model.learn(rng.choice([-0.5, 0.5], 145), int(rng.integers(4)), 0.0, rng.choice([-0.5, 0.5], 145), False)
    for a in range(4):
        r_a, e_a = model.predict(x, a)
        r_n, e_n = model.predict(rotate_observation(x, ACTION_ROTATION[a]), 0)  # the same move as "north"
        assert r_a == pytest.approx(r_n)
        full = np.zeros(145)
        full[52:84] = e_n  # the rotated world's enemy map ...
        back = np.empty(145)
        back[PERMS[a]] = full  # ... turned back: y[perm[i]] = y_rotated[i]
        np.testing.assert_array_equal(e_a, back[52:84])


def test_rotated_net_values_are_one_net_on_rotated_inputs():
    cfg = NetConfig(145, 6, lr=0.2, init_range=0.3)
    net = RotatedNet(cfg, PERMS, np.random.default_rng(0))
    ref = OAON(cfg, 1, np.random.default_rng(0))
    x = np.random.default_rng(1).choice([-0.5, 0.5], 145)
    for a in range(4):
        assert net.values(x)[a] == pytest.approx(ref.values(rotate_observation(x, a))[0], abs=1e-12)
        assert net.value(x, a) == pytest.approx(net.values(x)[a], abs=1e-12)
    # action symmetry: Q(rot(x, k), d) = Q(x, k + d)
    np.testing.assert_allclose(net.values(rotate_observation(x, 1)), np.roll(net.values(x), -1), atol=1e-12)
    ref_before = ref.update(rotate_observation(x, 2), 0, 0.9)
    assert net.update(x, 2, 0.9) == pytest.approx(ref_before, abs=1e-12)
    np.testing.assert_allclose(net.net.w1, ref.w1, atol=1e-12)
    with pytest.raises(ValueError, match="permutation"):
        RotatedNet(cfg, np.zeros((4, 145), dtype=int), np.random.default_rng(0))


def test_qcon_plans_while_learning_but_not_at_test():
    from connrl.experiments.protocol import run_trial
    from connrl.tasks.survival import SurvivalAgentParams, make_survival_agent

    env = SurvivalEnv("local")
    env.reset(seed=0)
    agent = make_survival_agent(SurvivalAgentParams("QCON-M", "local", "perfect"), env, np.random.default_rng(0))
    run_trial(env, agent, trial=0, learning=True, seed=1)
    assert agent.planner.hypothetical > 0 and agent.planner.steps > 0
    run_trial(env, agent, trial=0, learning=False, seed=1)
    assert agent.planner.hypothetical == 0  # reset at the test play's start and no planning at T = 0
