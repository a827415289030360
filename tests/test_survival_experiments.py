"""Ch. 4 experiments: every one runs through the CLI on the tiny profile; the results page and the play PNG."""

import json

import numpy as np
import pytest

from connrl import cli
from connrl.experiments.survival import (
    EXPERIMENTS,
    agreement,
    crossing,
    relation,
    render_play,
    results_section,
)

NAMES = [s.name for s in EXPERIMENTS]


def test_five_experiments_cover_chapter_4():
    assert NAMES == ["survival-study1", "survival-study2", "survival-planning", "survival-speedup", "survival-eval"]
    s1, s2 = EXPERIMENTS[0], EXPERIMENTS[1]
    assert len(s1.variants) == len(s2.variants) == 10  # 8 frameworks, -M with both models
    assert s1.params["representation"] == "global" and s2.params["representation"] == "local"
    assert s2.params["lr_scale"] == 2.0 and s1.params["lr_scale"] == 1.0
    full = s1.resolve("full")[0]
    assert (full["train_plays"], full["test_envs"], full["test_every"], s1.resolve("full")[1]) == (300, 50, 20, 7)
    assert EXPERIMENTS[4].resolve("full")[0]["eval_envs"] == 8000


@pytest.fixture(scope="module")
def tiny_out(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs")
    for name in NAMES:
        assert cli.main(["run", name, "--profile", "tiny", "--out", str(out), "--workers", "1", "--quiet"]) == 0
    return out


def test_tiny_runs_write_summaries(tiny_out):
    for name in NAMES:
        summary = json.loads((tiny_out / name / "summary.json").read_text())
        assert summary["profile"] == "tiny"
        assert (tiny_out / name / "curve.png").exists()
    s = json.loads((tiny_out / "survival-study1" / "summary.json").read_text())
    q = s["variants"]["QCON-T"]["quantities"]["final_food"]
    assert len(q["per_run"]) == 1 and 0 <= q["mean"] <= 15
    ev = json.loads((tiny_out / "survival-eval" / "summary.json").read_text())["variants"]["QCON-T"]["quantities"]
    assert ev["eval_food"]["thesis"] == 12.1


def test_tiny_runs_are_reproducible(tiny_out, tmp_path):
    cli.main(["run", "survival-speedup", "--profile", "tiny", "--out", str(tmp_path), "--workers", "1", "--quiet"])
    a = json.loads((tiny_out / "survival-speedup" / "summary.json").read_text())["variants"]
    b = json.loads((tmp_path / "survival-speedup" / "summary.json").read_text())["variants"]
    assert a == b


def test_results_section_and_play_png(tiny_out, tmp_path):
    text = results_section(tiny_out, doc=tmp_path / "RESULTS.md")
    for needle in ("Fig. 4.3", "Fig. 4.4", "4.4.2", "Table of 4.5", "Fig. 4.5", "4.3.4", "39.9%"):
        assert needle in text
    png = tmp_path / "figures" / "survival-play.png"
    assert png.exists() and png.stat().st_size > 10_000


def test_render_play_draws_a_readable_png(tmp_path):
    from connrl.envs.survival import SurvivalEnv
    from connrl.experiments.survival import _frame

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


def test_relation_symbols_and_agreement():
    assert relation([5, 5.1, 4.9], [1, 1.1, 0.9]) == ">"
    assert relation([1, 2, 3], [1, 2, 3]) == "~"
    assert relation([1, 1.1, 0.9], [5, 5.1, 4.9]) == "<"
    assert agreement(">", ">") == "agrees" and agreement(">=", ">") == "roughly"
    assert agreement("<", ">") == "**disagrees**" and agreement("~", ">") == "**disagrees**"
    assert crossing([0, 20, 40], [2.0, 6.0, 10.0], 8.0) == 30.0
    assert crossing([0, 20], [1.0, 2.0], 8.0) is None
    assert np.isclose(crossing([0, 20], [9.0, 10.0], 8.0), 0.0)
