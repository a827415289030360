"""Ch. 6's results section: the claims of 6.6 computed from run rows (by hand on made-up rows), the 6.7 accounting,
and the section drawn from tiny runs with Fig. 6.7's paths."""

import numpy as np

from connrl.report import recharge_claims as rc
from tests.tiny_runs import run_tiny


def _run(trials, docked_a, docked_b, docked_c, perf):
    return [{"trials": float(t), "docked_A": a, "docked_B": b, "docked_C": c, "performance": p}
            for t, a, b, c, p in zip(trials, docked_a, docked_b, docked_c, perf, strict=True)]


def test_rows_at_a_trial_and_at_the_end_are_means_over_runs():
    runs = [_run([0, 10, 20], [0, 0.5, 1.0], [0, 0, 0], [0, 0.2, 0.4], [0, 0.5, 1.0]),
            _run([0, 10, 20], [0, 0.3, 0.6], [0, 0, 0.2], [0, 0.0, 0.2], [0, 0.3, 0.8])]
    assert rc.at_trial(runs, "docked_A", 10) == 0.4
    assert rc.at_trial(runs, "docked_A", 15) == np.mean([1.0, 0.6])  # the first test at or after trial 15
    assert rc.at_trial(runs, "docked_A", 25) is None
    assert rc.at_end(runs, "docked_B") == np.mean([0.0, 0.2 / 3])  # over the last 3 tests of each run
    assert rc._rooms(runs, 20) == "0.80 / 0.10 / 0.30"


def test_holds_criteria():
    assert rc._yes(0.6, 0.5, 0.5) == "yes" and rc._yes(0.6, 0.4, 0.5) == "no" and rc._yes(None, None, 0.5) == "—"
    assert rc._cmp(0.2, 1.0, 0.75) == "yes"  # clearly worse: under 75 % of Exp. 3's
    assert rc._cmp(0.8, 1.0, 0.75) == "no"
    assert rc._cmp(0.8, 1.0, 0.75, lower=False) == "yes"  # comparable: at least 75 %


def test_chapter_6_section_holds_every_experiment_the_claims_and_the_paths(tmp_path):
    from connrl.report import recharge

    for name in ("recharge-flat", "recharge-behaviours", "recharge-long-delay", "recharge-together"):
        run_tiny(name, tmp_path)
    md = recharge.results_section(tmp_path, tmp_path / "docs" / "RESULTS.md")
    for name in ("recharge-flat", "recharge-behaviours", "recharge-long-delay", "recharge-together"):
        assert f"### {name}" in md
    assert "### The claims of 6.6 and 6.7 beside ours" in md
    assert "| ours, Exp. 1 | 497 (10 recharging lessons) |" in md  # the shipped lessons' teaching steps
    assert (tmp_path / "docs" / "figures" / "recharge-behaviours-paths.png").exists()
