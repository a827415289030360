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
    assert "**Verdict:** —. Of the 0 runs" in text  # no run's model was fixed
