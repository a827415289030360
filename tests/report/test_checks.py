"""The Ch. 4 / Ch. 5 helpers that apply the page's verdict rules (connrl.report.checks), on constructed runs."""

import numpy as np
import pytest

from connrl.report import checks, verdicts
from connrl.report.checks import AGREES, CONTRADICTED, OPEN

TIGHT = np.array([-0.1, 0.0, 0.1, 0.05, -0.05, 0.0, 0.02, -0.02])


def test_relation_check_per_symbol():
    hi, lo = list(10 + TIGHT), list(5 + TIGHT)
    assert checks.relation_check(hi, lo, ">")[0] == AGREES
    assert checks.relation_check(lo, hi, ">")[0] == CONTRADICTED
    assert checks.relation_check(lo, hi, "<")[0] == AGREES
    assert checks.relation_check(hi, list(10.2 + TIGHT), "~")[0] == AGREES  # 2 % apart, tight: same
    assert checks.relation_check(hi, lo, "~")[0] == CONTRADICTED
    assert checks.relation_check(hi, list(10 + TIGHT[::-1]), ">=")[0] == AGREES  # not separated, same within 10 %
    assert checks.relation_check(lo, hi, ">=")[0] == CONTRADICTED
    noisy_a, noisy_b = [10, 14, 6, 12], [9, 13, 4, 11]
    assert checks.relation_check(noisy_a, noisy_b, "~")[0] == OPEN
    assert checks.relation_check(noisy_a, noisy_b, ">")[0] == OPEN
    assert checks.relation_check([1.0], [2.0, 3.0], ">")[0] == OPEN  # one run: no test


def test_claim_verdict_and_tally():
    assert checks.claim_verdict([AGREES, AGREES]) == verdicts.REPRODUCED
    assert checks.claim_verdict([AGREES, OPEN]) == verdicts.OPEN  # agreeing parts do not outvote undecided ones
    assert checks.claim_verdict([AGREES, CONTRADICTED]) == verdicts.PARTLY
    assert checks.claim_verdict([CONTRADICTED, OPEN]) == verdicts.NOT_REPRODUCED
    assert checks.claim_verdict([OPEN, OPEN]) == verdicts.OPEN
    assert checks.claim_verdict([]) == verdicts.OPEN
    assert checks.tally([AGREES, OPEN, AGREES]) == "2 agrees, 0 contradicted, 1 undetermined (of 3)"


def test_compare_runs_leaves_out_missing_runs_and_refuses_one_run():
    assert checks.compare_runs([1.0, None], [1.0, 2.0]) is None
    assert "no test" in checks.comparison_text(None, [1.0], [1.0, 2.0])
    c = checks.compare_runs(list(10 + TIGHT), list(10 + TIGHT) + [None])
    assert c.verdict == verdicts.SAME and checks.same_word(c) == "same"
    c = checks.compare_runs([10, 14, 6, 12], [9, 13, 4, 11])
    assert checks.same_word(c).startswith("undetermined with 4 runs")


def test_ordering_check_needs_two_runs_a_side():
    runs = {"a": [3.0, 3.1, 2.9], "b": [2.0, 2.1, 1.9], "c": [1.0, 1.1, 0.9]}
    assert checks.ordering_check(runs, ["a", "b", "c"])[0] == "agrees"
    word, lines = checks.ordering_check({**runs, "c": [1.0]}, ["a", "b", "c"])
    assert word == OPEN and "not tested" in lines[1]
    assert checks.ordering_verdict("contradicted") == verdicts.NOT_REPRODUCED


def test_matched_passes_pairs_copy_epochs_with_trials():
    copy_xs = [0, 1, 2, 5, 10, 20]
    copy_curves = [(copy_xs, [0, 0, 0, 0, -0.7, 1.0]), (copy_xs, [0, 0, 0, 0, -0.6, 1.2]),
                   (copy_xs + [21], [0, 0, 0, 0, -0.2, 1.4, 1.5])]  # stopped later: a longer curve still counts
    rl_xs, rl_runs = [0, 10, 20, 30], [[0, -0.8, 0.5, 1.0], [0, -0.9, 0.3, 1.1]]
    rows = checks.matched_passes(copy_curves, rl_xs, rl_runs)
    assert [k for k, *_ in rows] == [10, 20]  # 0 passes left out
    k, a, b, c = rows[0]
    assert a == pytest.approx(-0.5) and b == pytest.approx(-0.85) and c.n == (3, 2)
    assert checks.matched_passes(copy_curves, rl_xs, rl_runs, margin=2.0)[0][3].margin == 2.0
    assert checks.matched_passes(copy_curves[:1], rl_xs, rl_runs[:1])[0][3] is None


def test_meets_claims_put_one_claim_per_thesis_number():
    verdicts.BOARD.clear()
    summary = {"runs_per_variant": 2, "profile": "full", "variants": {
        "A": {"quantities": {"t": {"thesis": 10, "mean": 8.0, "per_run": [7, 9], "runs_reaching": 2,
                                   "better": "lower", "meets_thesis": True},
                             "f": {"thesis": None, "mean": 1.0, "per_run": [1, 1]}}},
        "B": {"quantities": {"t": {"thesis": 10, "mean": None, "per_run": [None, None], "runs_reaching": 0,
                                   "better": "lower", "meets_thesis": False}}}}}
    claims = checks.meets_claims(summary, "Fig. X", "5.6", "heading")
    assert [c.verdict for c in claims] == [verdicts.REPRODUCED, verdicts.NOT_REPRODUCED]
    assert verdicts.BOARD == claims and "≤" in claims[0].criterion
    verdicts.BOARD.clear()


def test_a_p_value_below_double_precision_is_not_printed_as_zero():
    far = [100.0 + k * 0.01 for k in range(7)]
    near = [0.0 + k * 0.01 for k in range(7)]
    word, text = checks.relation_check(far, near, ">")
    assert word == AGREES and text == "better (p < 1e-15)"
    assert checks.p_text(0.0123) == "p = 0.012"
