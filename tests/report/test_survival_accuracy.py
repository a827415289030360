"""4.4.3's model accuracy: the per-play error columns of the -M runs, the block curves and when they settle."""

import numpy as np
import pytest

from connrl.experiments.survival import SurvivalParams, run_survival
from connrl.report.survival_accuracy import _scale_lines, block_curve, model_accuracy, settles
from tests.tiny_runs import run_tiny


def test_learned_model_runs_record_errors_per_play_and_probes_every_fifth():
    p = SurvivalParams(framework="QCON-M", model="learned", train_plays=6, test_envs=1, test_every=0)
    rows = [r for r in run_survival(p, np.random.default_rng(0)).rows if r["kind"] == "train"]
    assert all("model_reward_abs" in r and "model_reward_sq" in r and "model_enemy_bits" in r for r in rows)
    assert all(r["model_reward_sq"] >= r["model_reward_abs"] ** 2 - 1e-12 for r in rows)  # mean of squares >= square
    assert [r["plays"] for r in rows if "model_probe_reward_abs" in r] == [1, 5]
    assert [r["plays"] for r in rows if "model_probe_reward_sq" in r] == [1, 5]
    perfect = run_survival(SurvivalParams(framework="QCON-M", model="perfect", train_plays=2, test_envs=1,
                                          test_every=0), np.random.default_rng(0)).rows
    assert not any("model_probe_reward_abs" in r for r in perfect)  # the perfect model has nothing to measure


def test_block_curve_averages_plays_then_runs():
    run_a = [{"kind": "train", "plays": float(k), "e": float(k <= 10)} for k in range(1, 21)]
    run_b = [{"kind": "train", "plays": float(k), "e": 0.5} for k in range(1, 21)] + [{"kind": "test", "plays": 0.0}]
    ends, curve, last = block_curve([run_a, run_b], "e")
    assert ends.tolist() == [10, 20] and curve.tolist() == [0.75, 0.25] and last.tolist() == [0.0, 0.5]


def test_settles_is_the_first_block_after_which_the_curve_stays_near_its_tail():
    ends = np.arange(10, 310, 10)
    curve = np.where(ends <= 60, 2.0, 1.0)  # drops to its level after play 60
    assert settles(ends, curve) == 70
    curve[3] = 1.0  # touching the level early does not count
    assert settles(ends, curve) == 70
    assert settles(ends[:5], curve[:5]) is None  # no plays after 200: no level to settle to


def test_section_reads_the_stored_runs(tmp_path):
    for name in ("survival-study1", "survival-study2"):
        run_tiny(name, tmp_path)
    text = "\n".join(model_accuracy(tmp_path, tmp_path / "docs" / "RESULTS.md"))
    assert "### 4.4.3: the learned model's prediction accuracy" in text
    rows = [line for line in text.splitlines() if line.startswith("| survival-study")]
    assert len(rows) == 2 * 2 * 6 and all(len(line.split("|")) == 10 for line in rows)  # studies x agents x errors
    assert "in squared error, the error they are trained to reduce" in text
    assert (tmp_path / "docs" / "figures" / "survival-model-accuracy.png").exists()
    assert model_accuracy(tmp_path / "none", tmp_path / "x.md") == []


@pytest.mark.parametrize("column", ["model_reward_abs", "model_probe_enemy_bits"])
def test_block_curve_of_a_missing_column_is_empty(column):
    assert block_curve([[{"kind": "train", "plays": 1.0}]], column)[0].size == 0


@pytest.mark.parametrize(("final", "word"), [(0.0, "and beat it in squared error"),
                                             (1.0, "and do **not** beat it in squared error")])
def test_scale_lines_compare_the_squared_error_with_predicting_zero(final, word):
    probes = [{"column": "model_probe_reward_sq", "final": final, "rep": rep} for rep in ("global", "local")]
    assert word in _scale_lines(probes)[0]
