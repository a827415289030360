"""Issue 44's search of the robot world family: its scoring rules on hand-made curves, the caption filter, and the
command end to end on a smoke length (resume, refusal, the results section)."""

import math

import pytest

from connrl.cli import main
from connrl.experiments import world_family as wf
from connrl.report import world_family as report


def test_score_by_hand():
    flat = [0.0] * 31
    ramp = [min(3.0, 0.01 * 10 * i) for i in range(31)]  # 2.5 at trial 250
    late = [min(3.0, 0.01 * 10 * i * 0.9) for i in range(31)]  # 2.52 at trial 280
    s = wf.score([ramp, late], [250, 280])
    assert s["T"] == 270  # mean 0.95 x 0.1 x i >= 2.5 first at i = 27 (2.565)
    assert s["F"] == 0 and s["accepted"]
    assert s["loss"] == pytest.approx(abs(math.log(270 / 280)), abs=1e-4)
    s = wf.score([flat, ramp], [None, 250])  # mean peaks at 1.5
    assert s["T"] is None and not s["accepted"]
    assert s["loss"] == pytest.approx(math.log(300 / 280) + (2.5 - 1.5) / 2.5, abs=1e-4)
    fast = [3.0] * 31
    s = wf.score([fast] * 3 + [flat] * 4, [0, 0, 0, None, None, None, None])  # mean 1.29: never
    assert s["T"] is None and s["F"] == 4
    s = wf.score([ramp] * 7, [250] * 7)
    assert s["accepted"] and wf.score([fast] * 7, [0] * 7)["T"] == 0 and not wf.score([fast] * 7, [0] * 7)["accepted"]


def test_distance_by_hand():
    assert wf.distance(dict(wf.TODAY)) == 0
    w = dict(wf.TODAY) | {"door_width": 57.0, "collision": "partial", "dp_lateral": 1.75}
    assert wf.distance(w) == pytest.approx(9 / 36 + 1 + 0.75 / 1.5)


def test_caption_filter_on_the_world_before_issue_44_and_the_spec_threshold():
    l3, l4 = wf.caption_shares(dict(wf.TODAY))
    assert l3 > 0.8 and l4 > 0.8  # docs/RECONSTRUCTION.md step 1: 44 in shows four edges in ~90 % of scans
    l3, l4 = wf.caption_shares(dict(wf.TODAY) | {"edge_jump": 24.0})
    assert max(l3, l4) < wf.CAPTION_SHARE  # 24 in: usually six bits


def test_command_end_to_end_on_a_smoke_length_resumes_and_reports(tmp_path, capsys):
    out = tmp_path / "family"
    args = ["world-family", "--out", str(out), "--trials", "10", "--budget", "3", "--workers", "1", "--quiet"]
    assert main(args) == 0
    first = wf.read_json(out / "search.json")
    assert first["trials"] == 10 and len(first["worlds"]) == 3
    assert all(set(r) >= {"world", "caption_ok", "T", "F", "loss", "accepted"} for r in first["worlds"])
    assert (out / "search.csv").read_text().count("\n") == 4
    pred = wf.read_json(out / "predictions.json")
    assert pred["worlds"][0]["number"] == "today" and set(pred["worlds"][0]["cases"]) >= {"no teaching", "3 lessons"}
    # resumed: the same worlds, nothing asked again; a larger budget adds worlds after them
    assert main([*args[:-3], "--budget", "4", "--workers", "1", "--quiet", "--stage", "search"]) == 0
    again = wf.read_json(out / "search.json")["worlds"]
    assert again[:3] == first["worlds"] and len(again) == 4
    with pytest.raises(SystemExit, match="10 trials per run, not 20"):
        main(["world-family", "--out", str(out), "--trials", "20", "--quiet", "--stage", "search"])
    with pytest.raises(SystemExit, match="stage predict reads"):
        main(["world-family", "--out", str(tmp_path / "empty"), "--stage", "predict"])
    results = tmp_path / "results"
    (results / "world-family").mkdir(parents=True)
    for name in ("search.json", "recheck.json", "predictions.json"):
        (results / "world-family" / name).write_bytes((out / name).read_bytes())
    text = report.results_section(results, tmp_path / "docs" / "RESULTS.md")
    assert "## The robot world as a family" in text and "4 worlds" in text
    assert (tmp_path / "docs" / "figures" / "world-family.png").exists()


def test_score_edge_cases_by_hand():
    fast, flat = [3.0] * 31, [0.0] * 31
    s = wf.score([fast] * 7, [0] * 7)  # at 2.5 before learning: T = 0, scored as trial 10, never accepted
    assert s["T"] == 0 and not s["accepted"] and s["loss"] == pytest.approx(abs(math.log(10 / 280)), abs=1e-4)
    ramp = [min(3.0, 0.01 * 10 * i) for i in range(31)]
    s = wf.score([ramp, []], [250, None])  # a diverged run: no curve, failing, left out of the mean
    assert s["T"] == 250 and s["F"] == 1 and len(s["mean_curve"]) == 31
    s = wf.score([[], []], [None, None])
    assert s["T"] is None and s["F"] == 2 and s["mean_curve"] == []
    assert wf.score([flat, [9.0] * 31], [None, 0])["T"] == 0  # the shortfall term never goes below zero


def test_recheck_keeps_world_numbers_and_old_logs_resume(tmp_path):
    out = tmp_path / "family"
    out.mkdir()
    world = dict(wf.TODAY)
    row = {"number": 7, "world": world, "caption_ok": True, "T": 200, "F": 0, "loss": 0.3, "accepted": True}
    (out / "search.json").write_text(wf.strict_json({"stage": "search", "trials": 10, "worlds": [row]}))
    rows = wf.recheck(out, workers=1, executor="process", address=None, show=False)
    assert [r["number"] for r in rows] == [7] and wf.read_json(out / "recheck.json")["trials"] == 10
    old = tmp_path / "old"  # a log written before it kept "trials" and "batch": the protocol's 300, batches of 2
    old.mkdir()
    (old / "search.json").write_text(wf.strict_json({"stage": "search", "worlds": [row]}))
    assert wf.search(old, budget=1, workers=1, show=False, log=lambda line: None) == [row]
