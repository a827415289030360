"""Ch. 5 results section: tables, solution paths, geometry panels and notes."""

from __future__ import annotations

import json

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
    for name in ("robot-dp-geometry", "robot-dk-geometry"):
        run_tiny(name, tmp_path)
    md = robot.results_section(tmp_path, tmp_path / "docs" / "RESULTS.md")
    assert "**Door width and start heading**" in md and "**Docking tolerance**" in md
    assert "| 48-in doors, facing +-45, 10 lessons |" in md
    for name in ("robot-dp-geometry", "robot-dk-geometry"):
        assert (tmp_path / name / "panels.png").exists()
        assert (tmp_path / "docs" / "figures" / f"{name}-curves.png").exists()


def test_results_section_without_runs(tmp_path):
    assert "No Ch. 5 results yet" in robot.results_section(tmp_path, tmp_path / "RESULTS.md")
