"""The verdict rules on constructed samples, against printed t tables and hand arithmetic."""

import math

import numpy as np
import pytest

from connrl.report import verdicts
from connrl.report.verdicts import DIFFERENT, SAME, UNDETERMINED, compare, ordering, t_cdf, t_quantile


@pytest.mark.parametrize("p, df, table", [(0.95, 1, 6.314), (0.95, 6, 1.943), (0.975, 6, 2.447), (0.975, 12, 2.179),
                                          (0.95, 30, 1.697), (0.975, 1e6, 1.960), (0.995, 4, 4.604)])
def test_t_quantiles_match_the_printed_table(p, df, table):
    assert t_quantile(p, df) == pytest.approx(table, abs=5e-4)
    assert t_cdf(table, df) == pytest.approx(p, abs=2e-4)
    assert t_quantile(1 - p, df) == pytest.approx(-table, abs=5e-4)


def test_a_true_equivalence_is_called_same():
    a = 10 + np.array([-0.2, -0.1, 0.0, 0.1, 0.2] * 4)  # 20 runs, mean 10
    b = a + 0.1
    c = compare(a, b)  # margin 10 % of 10 = 1
    assert c.verdict == SAME and c.margin == pytest.approx(1.0) and c.diff == pytest.approx(0.1)
    # by hand: var of a = b = 0.02 * 20 / 19 per run; SE = sqrt(2 * var / 20); df = 38
    se = math.sqrt(2 * (np.var(a, ddof=1) / 20))
    assert c.se == pytest.approx(se) and c.df == pytest.approx(38)
    assert c.ci[1] == pytest.approx(0.1 + t_quantile(0.95, 38) * se)


def test_a_true_difference_is_called_different():
    a = np.array([1.0, 1.1, 0.9, 1.0, 1.05, 0.95, 1.0])
    c = compare(a, a + 0.5)
    assert c.verdict == DIFFERENT and c.p_difference < 1e-6


def test_no_significant_difference_with_few_noisy_runs_is_undetermined_not_same():
    a = np.array([1.0, 3.0, 0.5, 2.5])
    b = np.array([1.4, 3.6, 0.8, 2.9])  # 18 % higher, far inside the noise
    c = compare(a, b)
    assert c.verdict == UNDETERMINED and c.runs_needed is not None and c.runs_needed > 4
    assert "undetermined with 4 runs" in c.text()
    # the old rule ("within 2 SE") would have called it the same
    assert abs(c.diff) < 2 * c.se


def test_fewer_than_two_runs_a_side_is_refused():
    with pytest.raises(ValueError, match="at least 2"):
        compare([1.0], [1.0, 2.0])


def test_an_ordering_is_checked_pair_by_pair():
    rng = np.random.default_rng(0)
    runs = {"fast": 3 + 0.05 * rng.standard_normal(8), "mid": 2 + 0.05 * rng.standard_normal(8),
            "slow": 1 + 0.05 * rng.standard_normal(8)}
    assert ordering(runs, ["fast", "mid", "slow"])[0] == "agrees"
    verdict, lines = ordering(runs, ["fast", "slow", "mid"])  # the ends in order, the middle pair reversed
    assert verdict == "contradicted" and "reversed" in lines[1]
    runs["tie"] = runs["mid"] + 0.001
    assert ordering(runs, ["fast", "mid", "tie"])[0] == UNDETERMINED


@pytest.mark.parametrize("shift", [0.02, 0.15, 0.3])  # toward "same", toward "different"
def test_the_runs_said_to_decide_do_decide_and_no_fewer_would(shift):
    """runs_needed: samples of that many runs a side, with the same means and spreads, decide; one run fewer does
    not (t quantiles, not the normal approximation that once said 6 where 7 did not decide)."""
    a = np.array([1.0, 1.6, 0.7, 1.3, 0.9, 1.5, 1.1])
    b = a[::-1] + shift
    c = compare(a, b)
    assert c.verdict == UNDETERMINED and c.runs_needed > a.size

    def like(x, n):  # n runs with x's mean and standard deviation
        z = np.linspace(-1.0, 1.0, n)
        return x.mean() + x.std(ddof=1) * (z - z.mean()) / z.std(ddof=1)

    assert compare(like(a, c.runs_needed), like(b, c.runs_needed)).verdict != UNDETERMINED
    if c.runs_needed - 1 > a.size:
        assert compare(like(a, c.runs_needed - 1), like(b, c.runs_needed - 1)).verdict == UNDETERMINED


def test_scoreboard_tallies_checks_by_setting_and_rechecks_apart():
    t45, t43 = "Table 4.5: plays to reach 8", "4.4.3: the learned model never nearly perfect"
    rows = [verdicts.Claim(t45, "4.5", "t", "o", "c", verdicts.REPRODUCED),
            verdicts.Claim(t45, "4.5", "t", "o", "c", verdicts.NOT_REPRODUCED, setting="ours: a departure"),
            verdicts.Claim(t43, "4.4.3", "t", "o", "c", verdicts.NOT_REPRODUCED),
            verdicts.Claim(t45 + " (fresh seeds 2000-2006)", "4.5", "t", "o", "c", verdicts.NOT_REPRODUCED,
                           recheck=True)]
    lines = verdicts.scoreboard(rows)
    stated = f"Checks at the thesis's stated values: 1 {verdicts.REPRODUCED}, 1 {verdicts.NOT_REPRODUCED} (of 2)."
    assert stated in lines
    assert any(line.startswith("Checks at our departures") and line.endswith(f"1 {verdicts.NOT_REPRODUCED} (of 1).")
               for line in lines)
    assert any(line.startswith("Re-checks on seeds") and line.endswith(f"1 {verdicts.NOT_REPRODUCED} (of 1).")
               for line in lines)
    assert sum("Table 4.5: plays to reach 8 (fresh seeds 2000-2006)" in line for line in lines) == 1
    # Table 4.5's item is decided by its re-check, 4.4.3's by its one check: both not reproduced
    tally = next(line for line in lines if line.startswith("Thesis items:"))
    assert tally.startswith(f"Thesis items: 2 {verdicts.NOT_REPRODUCED}, ")


