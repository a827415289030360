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
