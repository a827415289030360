"""Ch. 7 results section: Table 7.1's best-5-of-6 measure and the section from tiny runs."""

import numpy as np
import pytest

from connrl.experiments import hidden_state as experiments
from connrl.report import hidden_state as hs


def test_best_5_of_6():
    assert hs.best_k_mean([300, 100, 200, 400, 500, 600]) == (300.0, 0)
    assert hs.best_k_mean([300, None, 200, 400, 500, 600]) == (400.0, 0)  # the failed run is dropped
    assert hs.best_k_mean([None, None, 200, 400, 500, 600], fail_value=1000) == (540.0, 1)
    assert hs.best_k_mean([None, None, 200, 400, 500, 600]) == (None, 1)


def test_best5_of_6_distribution_enumerates_every_subset():
    # 6 runs: the only subset is the runs themselves
    assert hs.best5_of_6_distribution([300, 100, 200, 400, 500, 600], 1000) == (300.0, 300.0, 300.0)
    # 7 runs, one failed (counts 1000, so it is never among the best five): 6 subsets drop a finished run
    # and keep the other five; the 7th drops the failure and keeps the best five of the six finished runs
    m, lo, hi = hs.best5_of_6_distribution([100, 200, 300, 400, 500, 600, None], 1000)
    subsets = [(200 + 300 + 400 + 500 + 600) / 5, (100 + 300 + 400 + 500 + 600) / 5,
               (100 + 200 + 400 + 500 + 600) / 5, (100 + 200 + 300 + 500 + 600) / 5,
               (100 + 200 + 300 + 400 + 600) / 5, (100 + 200 + 300 + 400 + 500) / 5,
               (100 + 200 + 300 + 400 + 500) / 5]
    assert m == pytest.approx(np.mean(subsets))
    assert lo == pytest.approx(np.percentile(subsets, 5)) and hi == pytest.approx(np.percentile(subsets, 95))


@pytest.mark.parametrize("name", [s.name for s in experiments.EXPERIMENTS])
def test_results_section_names_the_command_of_each_run(tiny_runs, tmp_path, name):
    md = hs.results_section(tiny_runs(name), tmp_path / "RESULTS.md")
    assert "Command: `connrl run " + name in md


def test_results_section_without_runs(tmp_path):
    assert "No Chapter 7 results stored yet" in hs.results_section(tmp_path, tmp_path / "RESULTS.md")


def test_model_parts_read_the_stored_runs(tmp_path):
    from connrl.report.hidden_state_models import frozen_model, imperfect_model
    from tests.tiny_runs import run_tiny
    assert imperfect_model(tmp_path, tmp_path / "R.md") == [] and frozen_model(tmp_path, tmp_path / "R.md") == []
    for name in ("cup-task1", "cup-task2-frozen"):
        run_tiny(name, tmp_path)
    doc = tmp_path / "docs" / "RESULTS.md"
    text = "\n".join(imperfect_model(tmp_path, doc))
    rows = [line for line in text.splitlines() if line.startswith("| 0 |")]
    assert len(rows) == 1 and len(rows[0].split("|")) == 8  # one tiny run, six columns
    assert "**Verdict:**" in text and (tmp_path / "docs" / "figures" / "cup-task1-model-error.png").exists()
    text = "\n".join(frozen_model(tmp_path, doc))
    assert "| model fixed after 300 trials | never | 0 | 0 |" in text  # tiny: 3 trials, never optimal
    assert "Where the fixed model fails here" in text  # the stored runs' note (not the re-check's)
    assert "**Verdict:** — (most runs fixed in time must stay optimal; partly: at least a quarter). Of the 0 " in text


def test_fresh_seed_rechecks_are_labelled_by_their_own_runs(tiny_runs, tmp_path):
    from connrl.report import verdicts
    verdicts.BOARD.clear()
    try:
        md = hs.results_section(tiny_runs("cup-task1-fresh", "cup-task1"), tmp_path / "RESULTS.md")
        tag = " (seeds 0-0, tiny profile: not the check)"  # a smoke run at seed 0 must not pass for the fresh check
        assert f"### Task 1: 2-cup collection (Fig. 7.5, 7.5.1){tag}" in md
        items = {c.item: c for c in verdicts.BOARD}
        assert not items["Fig. 7.5: 2-cup collection"].recheck and items["Fig. 7.5: 2-cup collection" + tag].recheck
    finally:
        verdicts.BOARD.clear()
    full = {"base_seed": 3000, "runs_per_variant": 20, "profile": "full"}
    assert hs.fresh_tag(full) == " (fresh seeds 3000-3019)"
    assert hs.fresh_tag({**full, "runs_per_variant": 5}) == " (seeds 3000-3004, full profile: not the check)"


def test_fixed_model_verdict_needs_most_runs_by_hand():
    from connrl.report.hidden_state_models import fixed_verdict
    assert fixed_verdict(0, 0) == "—"
    assert [fixed_verdict(k, 46) for k in (3, 11, 12, 23, 24)] == [
        "**not reproduced**", "**not reproduced**", "partly", "partly", "reproduced"]
