"""Ch. 5 results section: tables, solution paths, geometry panels and notes."""

from __future__ import annotations

import json

import numpy as np

from connrl.report import robot
from tests.tiny_runs import run_tiny


def test_tiny_run_and_results_section(tmp_path):
    run_tiny("robot-teaching-dp", tmp_path)
    summary = json.loads((tmp_path / "robot-teaching-dp" / "summary.json").read_text())
    assert summary["variants"]["10 lessons"]["quantities"]["trials_to_2.5"]["thesis"] == 10
    md = robot.results_section(tmp_path, tmp_path / "RESULTS.md")
    assert "robot-teaching-dp" in md and "| 10 lessons |" in md
    assert (tmp_path / "robot-teaching-dp" / "solution-paths.png").exists()


def test_geometry_sections_draw_panels_and_notes(tmp_path):
    for name in ("robot-teaching-dp", "robot-dp-copy", "robot-dp-calibration", "robot-dp-geometry",
                 "robot-dp-replay-order", "robot-dp-fresh", "robot-dk-geometry", "robot-dp-lesson-use"):
        run_tiny(name, tmp_path)
    md = robot.results_section(tmp_path, tmp_path / "docs" / "RESULTS.md")
    for head in ("**Calibration of issue 12**", "**Copy bound**", "**Each change of issue 12's calibration alone**",
                 "**Replay order**", "**Fresh seeds**", "**Docking tolerance**"):
        assert head in md, head
    assert "Changing one thing, 10 to 100 taught lessons" in md
    assert "| SPEC: 36-in doors, 24-in edges, 10 lessons |" in md and "| copy 10 lessons |" in md
    assert md.index("### robot-teaching-dp") < md.index("### robot-dp-copy") < md.index("### robot-dp-calibration")
    for name in ("robot-dp-geometry", "robot-dk-geometry"):
        assert (tmp_path / name / "panels.png").exists()
        assert (tmp_path / "docs" / "figures" / f"{name}-curves.png").exists()


def test_results_section_without_runs(tmp_path):
    assert "No Ch. 5 results yet" in robot.results_section(tmp_path, tmp_path / "RESULTS.md")


def test_speedup_tables_need_the_reference_row_to_reach_the_level():
    xs = np.arange(0, 310, 10)

    def curve(first):  # 0 before trial `first`, 6 from it on
        return xs, np.where(xs >= first, 6.0, 0.0) if first is not None else np.zeros(xs.size), 7

    keys = [("robot-teaching-dp", v) for v in ("no teaching", "3 lessons", "10 lessons")] + \
        [("robot-lambda-dp", v) for v in ("lambda=0", "lambda=0.3", "lambda=0.7")]
    md = "\n".join(robot._speedup_tables(dict(zip(keys, map(curve, (None, 200, 100, 280, 140, 70)), strict=True))))
    assert "| 10 taught lessons | 100 | — | 10 | 28 |" in md  # no teaching never reached 2.5: no speedup
    assert "| lambda = 0.7 | 70 | 4 | 65 | 4.3 |" in md  # 280 / 70


def test_chapter_6_section_shows_the_shipped_library_and_its_q_maps(tmp_path):
    from connrl.report import recharge

    run_tiny("recharge-behaviours", tmp_path)
    md = recharge.results_section(tmp_path, tmp_path / "docs" / "RESULTS.md")
    assert "## Chapter 6" in md and "| DP | 1500 | 10 | 25% |" in md
    assert "### recharge-behaviours" in md and "By start room" in md
    assert (tmp_path / "docs" / "figures" / "recharge-behaviours-rooms.png").exists()
    for name in ("behaviour-dp-q-map", "behaviour-dk-q-map"):
        assert (tmp_path / "docs" / "figures" / f"{name}.png").exists()


def test_speedup_bound_and_verdict():
    assert robot.speedup_bound(280, 10, 300) == (28.0, False)
    assert robot.speedup_bound(None, 180, 300) == (300 / 180, True)  # the reference never reached: a lower bound
    assert robot.speedup_bound(280, None, 300) == (None, False)
    assert robot._speedup_verdict(280, [("a", 20, 14), ("b", 10, 28)], 300)[0] == "reproduced"
    assert robot._speedup_verdict(None, [("a", 190, 14)], 300)[0] == "undetermined"  # bound 1.6 < 14: open
    assert robot._speedup_verdict(200, [("a", 190, 14)], 300)[0] == "not reproduced"
