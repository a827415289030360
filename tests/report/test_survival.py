"""Ch. 4 results section: the page, the play PNG, comparison symbols."""

import numpy as np
import pytest

from connrl.experiments.survival import EXPERIMENTS
from connrl.report import verdicts
from connrl.report.survival import _roughly_best, crossing, render_play, results_section
from connrl.report.survival_speedup import plays_verdict

NAMES = [s.name for s in EXPERIMENTS]


@pytest.fixture
def tiny_out(tiny_runs):
    return tiny_runs(*NAMES)


def test_results_section_and_play_png(tiny_out, tmp_path):
    text = results_section(tiny_out, doc=tmp_path / "RESULTS.md")
    for needle in ("Fig. 4.3", "Fig. 4.4", "4.4.2", "Table of 4.5", "Fig. 4.5", "4.3.4", "39.9%"):
        assert needle in text
    png = tmp_path / "figures" / "survival-play.png"
    assert png.exists() and png.stat().st_size > 10_000


@pytest.fixture
def board():
    verdicts.BOARD.clear()
    yield verdicts.BOARD
    verdicts.BOARD.clear()


def test_fresh_seed_check_repeats_the_verdicts_as_rechecks(tiny_out, tmp_path, board):
    text = results_section(tiny_out, doc=tmp_path / "RESULTS.md")
    tag = " (seeds 0-0, tiny profile: not the check)"  # tiny runs at seed 0 must not pass for the fresh check
    assert f"### Table of 4.5: Study 2 Q-agents, plays to reach 8 food per play{tag}" in text
    assert not [line for line in text.splitlines() if line.startswith("#") and "fresh seeds 2000" in line]
    items = {c.item: c for c in board}
    for item in ("Table 4.5: plays to reach 8", "Table 4.5: the ordering of the speedups",
                 "4.4.1: Q-agents' final performance unaffected by the representation",
                 "Table of 4.4.2 (experience replay)"):
        assert not items[item].recheck and items[item + tag].recheck
    # the re-check repeats the check's rule; issue 31's looser 1.5x rule is said in the section, not scored again
    assert "1.5×" not in items["Table 4.5: plays to reach 8" + tag].criterion
    assert "1.5×" not in items["Table 4.5: plays to reach 8"].criterion
    assert not [i for i in items if "within 1.5" in i] and "Within 1.5× the thesis's plays" in text


def test_plays_to_8_verdict_by_hand():
    fast = {"QCON": 190.0, "QCON-R": 80.0, "QCON-T": 60.0}  # thesis 200 / 80 / 60
    assert plays_verdict(fast) == verdicts.REPRODUCED
    assert plays_verdict({**fast, "QCON-T": 61.0}) == verdicts.PARTLY
    assert plays_verdict({**fast, "QCON-T": 90.0}, factor=1.5) == verdicts.REPRODUCED  # 60 x 1.5 = 90
    assert plays_verdict({**fast, "QCON-T": 91.0}, factor=1.5) == verdicts.PARTLY
    assert plays_verdict({"QCON": None, "QCON-R": 300.0}, factor=1.5) == verdicts.NOT_REPRODUCED


def test_render_play_draws_a_readable_png(tmp_path):
    from connrl.envs.survival import SurvivalEnv
    from connrl.tasks.survival import _frame

    env = SurvivalEnv("global")
    env.reset(seed=0)
    frames = [_frame(env)]
    for a in [0, 0, 3, 3, 2]:
        env.step(a)
        frames.append(_frame(env))
    path = render_play(frames, tmp_path / "play.png", n_panels=3)
    import matplotlib.image as mpimg

    img = mpimg.imread(path)
    assert img.shape[0] > 300 and img.shape[1] > 900  # three panels side by side


def test_roughly_the_best_needs_the_same_or_better_not_just_no_difference():
    best = [10.0, 10.1, 9.9, 10.0, 10.05, 9.95]
    assert _roughly_best(best, [x + 0.1 for x in best])[0] == "agrees"  # same within 10 %
    assert _roughly_best(best, [x + 3 for x in best])[0] == "agrees"  # significantly better
    assert _roughly_best(best, [x - 3 for x in best])[0] == "contradicted"
    assert _roughly_best([10, 14, 6, 12], [9, 13, 4, 11])[0] == "undetermined"  # noisy: decides neither


def test_crossing():
    assert crossing([0, 20, 40], [2.0, 6.0, 10.0], 8.0) == 30.0
    assert crossing([0, 20], [1.0, 2.0], 8.0) is None
    assert np.isclose(crossing([0, 20], [9.0, 10.0], 8.0), 0.0)
