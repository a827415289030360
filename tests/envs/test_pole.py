"""Pole balancing (App. C): physics against an independent formulation, rewards, starts, check_env."""

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import connrl.envs  # noqa: F401
from connrl.envs.pole import TEST_START_ANGLES_DEG, PoleBalancingEnv, pole_step, sgn

G, MC, MP, L, MUC, MUP, TAU = 9.8, 1.0, 0.1, 0.5, 0.0005, 0.000002, 0.02


def reference_step(s, force):
    """App. C written as the coupled linear system in (x_acc, theta_acc), solved numerically.

    cart:  (mc+mp) x_acc + mp l cos(th) th_acc = F + mp l th_dot^2 sin(th) - muc sgn(x_dot)
    pole:  cos(th) x_acc + 4/3 l th_acc       = g sin(th) - mup th_dot / (mp l)
    Eliminating x_acc gives the closed form printed in App. C; solving the system is an independent route.
    """
    x, xd, th, thd = s
    a = np.array([[MC + MP, MP * L * math.cos(th)], [math.cos(th), 4.0 / 3.0 * L]])
    b = np.array([force + MP * L * thd**2 * math.sin(th) - MUC * (1.0 if xd >= 0 else -1.0),
                  G * math.sin(th) - MUP * thd / (MP * L)])
    xacc, thacc = np.linalg.solve(a, b)
    return (x + TAU * xd, xd + TAU * xacc, th + TAU * thd, thd + TAU * thacc)


def test_golden_trajectory_matches_the_independent_formulation():
    rng = np.random.default_rng(0)
    s = r = (0.1, 0.0, 0.03, 0.0)
    for _ in range(300):
        f = 10.0 if rng.random() < 0.5 else -10.0
        s, r = pole_step(s, f), reference_step(r, f)
        np.testing.assert_allclose(s, r, rtol=1e-10, atol=1e-12)


def test_first_step_by_hand():
    # from rest, upright, pushing right: theta_acc = (cos0 * (-10 + muc)/1.1) / (0.5 * (4/3 - 0.1/1.1))
    th_acc = ((-10.0 + MUC) / 1.1) / (0.5 * (4.0 / 3.0 - 0.1 / 1.1))
    x_acc = (10.0 + 0.1 * 0.5 * (0.0 - th_acc) - MUC) / 1.1
    s = pole_step((0.0, 0.0, 0.0, 0.0), 10.0)
    assert s == pytest.approx((0.0, TAU * x_acc, 0.0, TAU * th_acc), abs=1e-15)


def test_sgn_of_zero_is_plus_one():
    assert sgn(0.0) == 1.0 and sgn(-1e-9) == -1.0


def test_failure_gives_minus_one_and_terminates():
    env = PoleBalancingEnv()
    env.reset(options={"theta_deg": 11.0})
    rewards = []
    for _ in range(200):
        _, r, term, trunc, _ = env.step(0)
        rewards.append(r)
        if term:
            break
    assert term and not trunc and rewards[-1] == -1.0 and set(rewards[:-1]) <= {0.0}
    assert abs(env.state[2]) > 0.21


def test_time_limit_truncates_without_failure():
    env = PoleBalancingEnv(max_steps=3)
    env.reset(options={"theta_deg": 0.0})
    out = [env.step(i % 2) for i in range(3)]
    assert out[-1][3] and not out[-1][2] and out[-1][1] == 0.0


def test_observation_variants_and_scaling():
    full = PoleBalancingEnv()
    obs, _ = full.reset(options={"theta_deg": 2.0})
    assert obs.shape == (4,) and obs[2] == pytest.approx(math.radians(2.0) / 0.21)
    part = PoleBalancingEnv(observe="x_theta", normalize=False)
    obs, _ = part.reset(options={"theta_deg": 2.0, "x": 0.5})
    np.testing.assert_allclose(obs, [0.5, math.radians(2.0)])


def test_seeded_training_starts_are_reproducible_and_in_range():
    a, b = PoleBalancingEnv(), PoleBalancingEnv()
    for seed in range(5):
        oa, _ = a.reset(seed=seed)
        ob, _ = b.reset(seed=seed)
        np.testing.assert_array_equal(oa, ob)
        assert abs(a.state[0]) <= 1.2 and abs(a.state[2]) <= 0.06 and a.state[1] == a.state[3] == 0


def test_the_seven_test_starts():
    assert sorted(TEST_START_ANGLES_DEG) == [-3, -2, -1, 0, 1, 2, 3]


@pytest.mark.parametrize("env_id", ["connrl/PoleBalancing-v0", "connrl/PoleBalancingXTheta-v0"])
def test_check_env(env_id):
    check_env(gym.make(env_id).unwrapped, skip_render_check=True)


def test_bad_arguments():
    with pytest.raises(ValueError, match="observe"):
        PoleBalancingEnv(observe="velocity")
    env = PoleBalancingEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(2)
