"""The survival action models of 4.2.5 (perfect and learned) and planning inside a QCON-M trial."""

import numpy as np
import pytest

from connrl.envs.survival import ACTION_ROTATION, ROTATION_PERMUTATIONS, SurvivalEnv, rotate_observation
from connrl.tasks.survival_models import (
    LearnedModelConfig,
    LearnedSurvivalModel,
    PerfectSurvivalModel,
    _single_layer,
    _single_layer_train,
    probe_experiences,
)

PERMS = np.stack([ROTATION_PERMUTATIONS[ACTION_ROTATION[a]] for a in range(4)])


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


def test_qcon_plans_while_learning_but_not_at_test():
    from connrl.core.rollout import run_trial
    from connrl.tasks.survival import SurvivalAgentParams, make_survival_agent

    env = SurvivalEnv("local")
    env.reset(seed=0)
    agent = make_survival_agent(SurvivalAgentParams("QCON-M", "local", "perfect"), env, np.random.default_rng(0))
    run_trial(env, agent, trial=0, learning=True, seed=1)
    assert agent.planner.hypothetical > 0 and agent.planner.steps > 0
    run_trial(env, agent, trial=0, learning=False, seed=1)
    assert agent.planner.hypothetical == 0  # reset at the test play's start and no planning at T = 0


def test_probe_experiences_are_fixed_and_real():
    from connrl.tasks.survival_models import probe_experiences
    probes = probe_experiences("global", 7, 300)
    assert len(probes) == 300 and probes == probe_experiences("global", 7, 300)  # one yardstick (cached)
    rewards = {r for _, _, r, _ in probes}
    assert rewards <= {0.0, 0.4, -1.0} and {0.4, -1.0} <= rewards  # food and deaths are in it
    x, a, r, y = probes[0]  # the first is a real step of a fresh play from its seed: the env replays it
    env = SurvivalEnv("global")
    x0, _ = env.reset(seed=int(np.random.default_rng(7).integers(2**31 - 1)))
    np.testing.assert_array_equal(x, x0)
    y0, r0, *_ = env.step(a)
    np.testing.assert_array_equal(y, y0)
    assert r == r0
    other = probe_experiences("global", 8, 300)
    assert any(not np.array_equal(p[0], q[0]) for p, q in zip(probes, other, strict=True))


def test_probe_errors_of_a_blank_model_by_hand():
    from connrl.tasks.survival_models import probe_experiences
    env = SurvivalEnv("local")
    env.reset(seed=1)
    model = LearnedSurvivalModel(env, np.random.default_rng(0))
    model.w_r[:] = 0.0
    model.w_e[:] = 0.0  # predicts r = 0 and every enemy unit off (-0.5)
    probes = probe_experiences("local", 3, 200)
    errs = model.probe_errors(probes)
    assert errs["probe_reward_abs"] == pytest.approx(np.mean([abs(r) for _, _, r, _ in probes]))
    assert errs["probe_reward_sq"] == pytest.approx(np.mean([r * r for _, _, r, _ in probes]))
    assert errs["probe_enemy_bits"] == pytest.approx(np.mean([np.mean(y[52:84] > 0) for _, _, _, y in probes]))


def test_probe_errors_fall_as_the_model_learns_and_leave_it_alone():
    from connrl.tasks.survival_models import probe_experiences
    env = SurvivalEnv("global")
    env.reset(seed=1)
    model = LearnedSurvivalModel(env, np.random.default_rng(0))
    probes = probe_experiences("global", 5, 300)
    before = model.probe_errors(probes)
    w, state = model.w_r.copy(), model.rng.bit_generator.state
    assert model.probe_errors(probes) == before and np.array_equal(model.w_r, w)  # measuring changes nothing
    assert model.rng.bit_generator.state == state and model.errors["n"] == 0
    for _ in range(3):
        for x, a, r, y in probes:
            model.learn(x, a, r, y, r == -1.0)
    after = model.probe_errors(probes)
    assert after["probe_reward_abs"] < before["probe_reward_abs"]
    assert after["probe_enemy_bits"] < before["probe_enemy_bits"]


@pytest.mark.parametrize("representation", ["global", "local"])
def test_the_learned_reinforcement_net_beats_predicting_zero_on_other_plays(representation):
    """Issue 31: the reinforcement net's squared error, after learning on-line from one set of plays, is below that
    of predicting r = 0 on plays it never saw (at the old learning rate 0.1 it was above it)."""
    from connrl.tasks.survival_models import probe_experiences
    env = SurvivalEnv(representation)
    env.reset(seed=1)
    model = LearnedSurvivalModel(env, np.random.default_rng(0))
    for x, a, r, y in probe_experiences(representation, 21, 6000):
        model.learn(x, a, r, y, r == -1.0)
    held_out = probe_experiences(representation, 22, 1500)
    zero = np.mean([r * r for _, _, r, _ in held_out])
    assert model.probe_errors(held_out)["probe_reward_sq"] < 0.75 * zero


def test_pop_errors_by_hand_and_reset():
    """On-line errors: each experience is predicted before learning; pop_errors gives the means and starts again."""
    env = SurvivalEnv("local")
    x, _ = env.reset(seed=1)
    model = LearnedSurvivalModel(env, np.random.default_rng(0))
    model.w_r[:] = 0.0  # predicts r = 0 until it learns
    y, *_ = env.step(0)
    model.config = LearnedModelConfig(lr=1e-300)  # learning changes nothing measurable
    model.learn(x, 0, 0.4, y, False)
    model.learn(x, 1, -1.0, y, True)
    errs = model.pop_errors()
    assert errs["reward_abs"] == pytest.approx((0.4 + 1.0) / 2)
    assert errs["reward_sq"] == pytest.approx((0.16 + 1.0) / 2)  # the mean of squares, not the squared mean
    assert model.pop_errors()["reward_sq"] == 0.0 and model.errors["n"] == 0


def _predict_as_it_was(model, x, a):
    """``LearnedSurvivalModel.predict`` before issue 45 compiled it whole: NumPy around the two net kernels."""
    xr = np.ascontiguousarray(x[model.perms[a]])
    m = model._net(a)
    out_r, out_e = np.empty(1), np.empty(32)
    _single_layer(model.w_r[m], xr, 0, xr.shape[0], out_r)
    _single_layer(model.w_e[m], xr, model.MAPS[0], model.MAPS[1], out_e)
    enemy = np.empty(32)
    enemy[model.perms[a][52:84] - 52] = np.where(out_e > 0, 0.5, -0.5)
    return 2.0 * float(out_r[0]), enemy


def _train_as_it_was(model, row):
    n_in = (row.shape[0] - 2) // 2
    x, y, a, r = row[:n_in], row[n_in:2 * n_in], int(row[-2]), row[-1]
    perm = model.perms[a]
    xr, yr = np.ascontiguousarray(x[perm]), y[perm]
    m, c = model._net(a), model.config
    _single_layer_train(model.w_r[m], model.d_r[m], xr, 0, n_in, np.array([r]), 2.0, c.lr, c.momentum, np.empty(1))
    _single_layer_train(model.w_e[m], model.d_e[m], xr, model.MAPS[0], model.MAPS[1],
                        np.ascontiguousarray(yr[52:84]), 1.0, c.lr, c.momentum, np.empty(32))


@pytest.mark.parametrize("representation", ["global", "local"])
def test_the_compiled_model_is_the_numpy_one(representation):
    """predict, the training step and the error measure, compiled, give the code's former numbers bit for bit."""
    env = SurvivalEnv(representation)
    model, ref = (LearnedSurvivalModel(env, np.random.default_rng(8)) for _ in range(2))
    for x, a, r, y in probe_experiences(representation, 5, 300):
        got, want = model.predict(x, a), _predict_as_it_was(ref, x, a)
        assert got[0] == want[0]
        np.testing.assert_array_equal(got[1], want[1])
        assert model.prediction_error(x, a, r, y)[1] == float(np.mean(want[1] != y[model.ENEMY]))
        row = np.concatenate([x, y, [a, r]])
        model._train(row)
        _train_as_it_was(ref, row)
        for w, w_ref in ((model.w_r, ref.w_r), (model.w_e, ref.w_e), (model.d_r, ref.d_r), (model.d_e, ref.d_e)):
            np.testing.assert_array_equal(w, w_ref)


def test_the_perfect_model_restores_rather_than_resets_with_the_same_outcomes():
    """Each simulated action starts from the true state: the same outcomes and draws as ``set_state`` before each."""
    env = SurvivalEnv("global")
    env.reset(seed=3)
    for a in (0, 1, 2, 0, 3):
        env.step(a)
    model = PerfectSurvivalModel(env, np.random.default_rng(4))
    ref = PerfectSurvivalModel(env, np.random.default_rng(4))
    got = model.simulate(None, [0, 1, 2, 3, 1])
    state, want = env.get_state(), []
    for a in [0, 1, 2, 3, 1]:
        ref.scratch.set_state(state)
        y, r, terminated, _, _ = ref.scratch.step(a)
        want.append((y, float(r), bool(terminated)))
    for (y, r, t), (y_ref, r_ref, t_ref) in zip(got, want, strict=True):
        np.testing.assert_array_equal(y, y_ref)
        assert (r, t) == (r_ref, t_ref)
    got_state, ref_state = model.scratch.get_state(include_rng=True), ref.scratch.get_state(include_rng=True)
    assert got_state.keys() == ref_state.keys()
    for key, value in ref_state.items():
        np.testing.assert_equal(got_state[key], value)
