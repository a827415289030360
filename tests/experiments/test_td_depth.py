"""Fig. 5.2 (td-depth): the weights read off the code's lambda-returns, and D, against values worked by hand."""

import math

import numpy as np
import pytest

from connrl.experiments.td_depth import DepthParams, decay_depth, mean_lookahead, return_weights, run_depth
from connrl.report.td_depth import results_section
from tests.tiny_runs import run_tiny


def test_weights_are_the_lambda_returns_worked_by_hand():
    # R_t = r_t + gamma [(1 - lam) u_{t+1} + lam R_{t+1}] with u = 0 and one reward of 1 at t = 3, lam = 0.5:
    # R_3 = 1, R_2 = 0.5, R_1 = 0.25, R_0 = 0.125
    assert return_weights(0.5, 4).tolist() == [1.0, 0.5, 0.25, 0.125]
    # gamma < 1 shortens them: (gamma lam)^k
    assert return_weights(0.5, 3, gamma=0.8) == pytest.approx([1.0, 0.4, 0.16])


@pytest.mark.parametrize("lam, depth", [(math.exp(-1), 1.0), (math.exp(-1 / 3), 3.0), (math.exp(-0.4), 2.5)])
def test_depth_is_where_the_weight_reaches_one_over_e(lam, depth):
    # lam = e^(-1/D) makes lam^D = 1/e exactly: D = 1, 3 and 2.5 (between two steps)
    assert decay_depth(return_weights(lam, 50)) == pytest.approx(depth, rel=1e-9)


def test_depth_of_weights_that_do_not_decay_geometrically():
    # 1, 0.5, 0.1: 1/e = 0.368 lies between steps 1 and 2; log-linear: 1 + (ln 0.5 + 1) / (ln 0.5 - ln 0.1)
    assert decay_depth(np.array([1.0, 0.5, 0.1])) == pytest.approx(1 + (math.log(0.5) + 1) / math.log(5))
    assert decay_depth(np.array([1.0, 0.9, 0.8])) is None  # never reaches 1/e within the lesson


def test_mean_lookahead_by_hand():
    assert mean_lookahead(np.array([1.0, 1.0, 0.0])) == 0.5
    assert mean_lookahead(return_weights(0.5, 200)) == pytest.approx(1.0)  # lam / (1 - lam)


def test_run_matches_the_thesis_formula_and_refuses_short_lessons():
    result = run_depth(DepthParams(lams=(0.3, 0.9), steps=400), np.random.default_rng(0))
    assert result.curve_x == [0.3, 0.9]
    assert result.curve_y == pytest.approx([-1 / math.log(0.3), -1 / math.log(0.9)], rel=1e-9)
    assert result.metrics["depth_0.9"] == pytest.approx(9.4912, abs=1e-4) and result.metrics["depth_0.7"] is None
    with pytest.raises(ValueError, match="steps must exceed D"):
        DepthParams(lams=(0.99,), steps=50).check_combination()
    with pytest.raises(ValueError, match="lams must be numbers in"):
        DepthParams(lams=(1.0,))


def test_section_sets_ours_beside_the_thesis(tmp_path):
    run_tiny("td-depth", tmp_path)
    text = results_section(tmp_path, tmp_path / "docs" / "RESULTS.md")
    assert "| 0.9 | 9.491 | 9.491 |" in text and "**Verdict: reproduced**" in text
    assert (tmp_path / "docs" / "figures" / "td-depth-figure-5-2.png").exists()
    assert results_section(tmp_path / "none", tmp_path / "RESULTS.md") == ""
