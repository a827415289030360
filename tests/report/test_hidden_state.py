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
