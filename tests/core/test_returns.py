"""Pure TD(lambda) returns (5.1): the worked example of Ch. 2.1, lambda-returns by hand, cuts, clip."""

import numpy as np
import pytest

from connrl.core.returns import lambda_returns, td_lambda_target


@pytest.mark.parametrize("lam", [0.0, 0.3, 1.0])
def test_worked_example_of_chapter_2_1(lam):
    # States A, B, C predicted 0.8, 0.3, 0.6; the game is won (outcome 1) after C. gamma = 1.
    # TD(lambda) changes of 2.1: dA = (0.3-0.8) + (0.6-0.3) lam + (1-0.6) lam^2, dB = (0.6-0.3) + (1-0.6) lam,
    # dC = 1 - 0.6.
    returns = lambda_returns([0.0, 0.0, 1.0], [0.3, 0.6, 0.0], gamma=1.0, lam=lam)
    deltas = returns - np.array([0.8, 0.3, 0.6])
    assert deltas[0] == pytest.approx(-0.5 + 0.3 * lam + 0.4 * lam**2)
    assert deltas[1] == pytest.approx(0.3 + 0.4 * lam)
    assert deltas[2] == pytest.approx(0.4)


def test_lambda_returns_by_hand():
    r, u, g = [0.0, 1.0, -1.0], [0.5, 0.2, 0.0], 0.9
    lam = 0.5
    e2 = -1.0
    e1 = 1.0 + g * ((1 - lam) * 0.2 + lam * e2)
    e0 = 0.0 + g * ((1 - lam) * 0.5 + lam * e1)
    np.testing.assert_allclose(lambda_returns(r, u, g, lam), [e0, e1, e2])
    # lambda = 1 with backward replay is the discounted return actually received (5.1)
    np.testing.assert_allclose(lambda_returns(r, u, g, 1.0), [g * 1 + g * g * -1, 1 + g * -1, -1])
    # lambda = 0 is one-step Q-learning / TD(0)
    np.testing.assert_allclose(lambda_returns(r, u, g, 0.0), [g * 0.5, 1 + g * 0.2, -1.0])


def test_lambda_is_zero_at_the_last_step_and_where_asked():
    # the last step never looks at e'_{t+1}; a per-step lambda of 0 cuts the return (non-policy next action)
    out = lambda_returns([0.0, 0.0], [0.4, 0.7], 1.0, [1.0, 1.0])
    assert out[1] == pytest.approx(0.7)
    assert out[0] == pytest.approx(0.7)
    cut = lambda_returns([0.0, 0.0], [0.4, 0.7], 1.0, [0.0, 1.0])
    assert cut[0] == pytest.approx(0.4)


def test_clip_truncates_targets():
    out = lambda_returns([0.4, 0.4, 0.4], [2.0, 2.0, 2.0], 0.9, 0.0, clip=1.0)
    assert out.max() == 1.0
    assert td_lambda_target(1.0, 2.0, 0.0, 0.5, 0.0) == 2.0


def test_per_step_discounts_by_hand():
    """rlax's discount_t: e'_t = r_t + gamma_t [(1 - lam) u_{t+1} + lam e'_{t+1}], each step its own gamma_t."""
    r, u, d, lam = [1.0, 0.0, 2.0], [0.5, 0.4, 0.0], [0.5, 0.25, 0.9], 0.5
    # e2 = 2 + 0.9 * 0 = 2 (lambda 0 at the last step; u_3 = 0 after a terminal step)
    # e1 = 0 + 0.25 * (0.5 * 0.4 + 0.5 * 2) = 0.25 * 1.2 = 0.3
    # e0 = 1 + 0.5 * (0.5 * 0.5 + 0.5 * 0.3) = 1 + 0.5 * 0.4 = 1.2
    np.testing.assert_allclose(lambda_returns(r, u, d, lam), [1.2, 0.3, 2.0], rtol=0, atol=1e-15)
    # bootstrapped from u_3 = 0.8 (a truncated lesson): e2 = 2 + 0.9 * 0.8 = 2.72,
    # e1 = 0.25 * (0.2 + 0.5 * 2.72) = 0.39, e0 = 1 + 0.5 * (0.25 + 0.5 * 0.39) = 1.2225
    np.testing.assert_allclose(lambda_returns(r, [0.5, 0.4, 0.8], d, lam), [1.2225, 0.39, 2.72], rtol=0, atol=1e-15)
    # lambda = 1: the return received, discounted step by step: 1 + 0.5 * (0 + 0.25 * 2) = 1.25
    np.testing.assert_allclose(lambda_returns(r, u, d, 1.0), [1.25, 0.5, 2.0], rtol=0, atol=1e-15)


def test_a_constant_discount_array_equals_the_scalar():
    rng = np.random.default_rng(0)
    r, u = rng.normal(size=20), rng.normal(size=20)
    lams = np.where(rng.random(20) < 0.3, 0.0, 0.8)
    for gamma in (0.9, 0.99, 1.0):
        np.testing.assert_array_equal(lambda_returns(r, u, np.full(20, gamma), lams, clip=1.0),
                                      lambda_returns(r, u, gamma, lams, clip=1.0))


def test_grouped_discounts_give_the_original_lessons_returns():
    """State grouping (6.6.4): with lambda = 1 the grouped lesson's returns (rewards the discounted sums of the
    group's rewards, discounts gamma^k) are the original lesson's discounted returns at the centres."""
    from connrl.core.grouping import group_lesson
    from connrl.core.lessons import Lesson

    rng = np.random.default_rng(1)
    n, gamma = 40, 0.9
    x = np.cumsum(rng.normal(scale=0.4, size=(n + 1, 2)), axis=0)
    lesson = Lesson(x, rng.integers(0, 2, n), rng.normal(size=n), terminated=True)
    g = group_lesson(lesson, gamma, (0.5, 2.5), rng)
    assert len(g.lesson) < n  # some steps were grouped
    received = lambda_returns(lesson.rewards, np.zeros(n), gamma, 1.0)  # the discounted return from every step
    np.testing.assert_allclose(lambda_returns(g.lesson.rewards, np.zeros(len(g.lesson)), g.discounts, 1.0),
                               received[g.centres], rtol=1e-12)


@pytest.mark.parametrize("bad", [[0.9, 0.9], [[0.9, 0.9, 0.9]], np.full((3, 1), 0.9)])
def test_a_discount_array_of_another_length_is_refused(bad):
    with pytest.raises(ValueError, match=r"gamma must be a number or one discount per step \(3,\)"):
        lambda_returns([0.0, 0.0, 1.0], [0.0, 0.0, 0.0], bad, 0.5)
