"""6.2's complexity experiment: the thesis's optimal region size by hand, refusals, a tiny run's rows, and the
results section."""

import numpy as np
import pytest

from connrl.experiments.complexity import ComplexityParams, run_complexity, thesis_block
from tests.tiny_runs import run_tiny


def test_thesis_block_by_hand():
    # 2-D: k = 7.8 * 6561^0.6 = 1535 regions -> sqrt(6561 / 1535) = 2.07 -> the odd side 3
    assert thesis_block(6561, 2) == 3
    # 1-D: k = 4 * sqrt(2187) = 187 -> 2187 / 187 = 11.7 -> 11
    assert thesis_block(2187, 1) == 11


@pytest.mark.parametrize("kw, message", [({"j_min": 5, "j_max": 4}, "j_min <= j_max"),
                                          ({"j_max": 13}, "j_min <= j_max <= 12"),
                                          ({"rule": "smart"}, "rule must be one of")])
def test_bad_parameters_are_refused(kw, message):
    with pytest.raises(ValueError, match=message):
        ComplexityParams(**kw)


def test_a_run_counts_every_learner_at_every_size():
    r = run_complexity(ComplexityParams(dim=1, rule="greedy", j_min=3, j_max=5), np.random.default_rng(0))
    assert [row["n"] for row in r.rows] == [27, 81, 243]
    r2 = run_complexity(ComplexityParams(dim=2, rule="greedy", j_min=4, j_max=5), np.random.default_rng(0))
    assert [(row["n"], row["multi"] is None) for row in r2.rows] == [(81, False), (256, True)]  # side 16: no nesting
    for row in r.rows:
        # every learner tries each of the 2n state-actions it must know at least once
        assert row["flat"] >= 2 * row["n"] and row["multi"] >= 2 * row["n"] and row["single"] >= 2 * row["n"]
        assert row["best_block"] % 2 == 1 and row["best_k"] >= 2
    assert r.metrics["exponent_flat"] == pytest.approx(np.polyfit(np.log([27, 81, 243]),
                                                                  np.log([x["flat"] for x in r.rows]), 1)[0])


def test_results_section_from_a_tiny_run(tmp_path):
    from connrl.report import complexity

    run_tiny("complexity", tmp_path)
    md = complexity.results_section(tmp_path, tmp_path / "docs" / "RESULTS.md")
    assert "Fitted exponents" in md and "| 2-D, random walk |" in md
    assert (tmp_path / "docs" / "figures" / "complexity-executions.png").exists()
