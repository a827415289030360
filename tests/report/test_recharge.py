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


def _rows(trials, key, values):
    return [{"trials": float(t), key: v} for t, v in zip(trials, values, strict=True)]


def test_level_gain_and_same_tests_and_their_combination():
    assert rc.level_test([0.6, 0.7, 0.65, 0.62], 0.5)[0] == "yes"
    assert rc.level_test([0.52, 0.61, 0.44, 0.58], 0.5)[0] == rc.OPEN  # near the level, noisy: undetermined
    assert rc.level_test([0.0, 0.0], 0.0)[0] == "no"  # none docked is not above none
    assert rc.level_test([0.6], 0.5)[0] == rc.OPEN  # one run: no test
    assert rc.gain_test([0.2, 0.22, 0.19], [0.5, 0.55, 0.52], "x")[0] == "yes"
    assert rc.same_test([1.0, 1.02, 0.98, 1.0], [1.01, 0.99, 1.0, 1.02], "x")[0] == "yes"
    assert rc.combine(["yes", "yes"]) == rc.REPRODUCED and rc.combine(["yes", rc.OPEN]) == rc.OPEN
    assert rc.combine(["yes", "no"]) == rc.PARTLY and rc.combine(["no", rc.OPEN]) == rc.NOT_REPRODUCED


def test_exp2_room_a_is_judged_against_before_learning_and_most_of_the_room():
    """0.56 docked at trial 10 against 0.21 before learning: learnt, but "generally able" (more than half) is not
    shown with these runs; the old rule said it holds."""
    a = [[0.2, 0.6], [0.3, 0.4], [0.1, 0.7], [0.25, 0.55]]
    runs = {"e2": [[{"trials": 0.0, "docked_A": x0}, {"trials": 10.0, "docked_A": x10}] for x0, x10 in a]}
    (c,) = [c for c in rc.checks(runs, {}) if c.section == "6.6.2"]
    assert c.verdict == rc.OPEN and "learnt: trial 10 above trial 0" in c.tests and "better? yes" in c.tests


def _final(docked_b, perf=0.3):
    return [{"trials": float(t), "docked_A": 0.9, "docked_B": docked_b, "docked_C": 0.3, "performance": perf,
             "collisions": 0.1}
            for t in (130, 140, 150)]


def test_exp4_grouping_is_judged_against_the_arm_without_it():
    """Room B fails without grouping (0.03) -- and with it (0.03): grouping made no difference, not reproduced."""
    runs = {"e4n": [_final(b) for b in (0.0, 0.05, 0.03, 0.04, 0.03)],
            "e4g": [_final(b) for b in (0.03, 0.02, 0.04, 0.03, 0.03)]}
    (c,) = [c for c in rc.checks(runs, {}) if "grouping is what makes" in c.claim]
    assert c.verdict == rc.PARTLY and c.cause.startswith("measured")  # fails without grouping: yes; difference: no
    runs["e4g"] = [_final(b) for b in (0.6, 0.7, 0.65, 0.5, 0.6)]
    (c,) = [c for c in rc.checks(runs, {}) if "grouping is what makes" in c.claim]
    assert c.verdict == rc.REPRODUCED and c.cause == ""


def test_equal_cost_counts_the_library_and_the_own_library_variant():
    runs = {"e1": [_final(0.0, 0.04) for _ in range(3)], "e3": [_final(0.5, 0.7) for _ in range(3)],
            "own": [_final(0.3, p) for p in (0.3, 0.35, 0.32)]}
    q = {"e1": {"train_steps": [55000.0, 54000.0, 56000.0]}, "e3": {"train_steps": [19000.0, 20000.0, 21000.0]},
         "own": {"total_steps": [40000.0, 41000.0, 39000.0]}}
    found = [c for c in rc.checks(runs, q, library_steps=139108) if c.section == "6.7"]
    # 159,108 vs 55,000 steps; own library: cheaper and better, so no dearer and superior
    assert [c.verdict for c in found] == [rc.NOT_REPRODUCED, rc.REPRODUCED]
    assert "139,108" in found[0].ours
    q["own"]["total_steps"] = [90000.0, 95000.0, 92000.0]  # dearer beyond the margin: the cost part fails
    assert [c.verdict for c in rc.checks(runs, q, library_steps=139108) if c.section == "6.7"][1] == rc.PARTLY
    assert rc.library_steps({"DK": {"steps": 1}, "DP": {"steps": 2}}) == 3 and rc.library_steps({"DK": {}}) is None
    lines = rc.accounting({}, {"CHG": 497, "DK": 100}, {"DK": {"trials": 1500, "steps": 21471}})
    assert any("21,471 for the library" in x for x in lines) and any("not run yet" in x for x in lines)


def test_the_checks_go_on_the_scoreboard_linked_to_the_heading():
    from connrl.report import verdicts

    verdicts.BOARD.clear()
    rc.board(rc.checks({"e1": [_final(0.0, 0.04) for _ in range(3)]}, {}))
    assert verdicts.BOARD and all(c.anchor == rc.HEADING for c in verdicts.BOARD)
    verdicts.BOARD.clear()


def test_chapter_6_section_holds_every_experiment_the_claims_and_the_paths(tmp_path):
    from connrl.report import recharge

    for name in ("recharge-flat", "recharge-behaviours", "recharge-long-delay", "recharge-together"):
        run_tiny(name, tmp_path)
    md = recharge.results_section(tmp_path, tmp_path / "docs" / "RESULTS.md")
    for name in ("recharge-flat", "recharge-behaviours", "recharge-long-delay", "recharge-together"):
        assert f"### {name}" in md
    assert "### The claims of 6.6 and 6.7 beside ours" in md and "Quantities we tuned" not in md  # page top
    assert "| ours, Exp. 1 | 501 (10 recharging lessons) |" in md  # the shipped lessons' teaching steps
    assert (tmp_path / "docs" / "figures" / "recharge-behaviours-paths.png").exists()
