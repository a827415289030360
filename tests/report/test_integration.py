"""Ch. 8's results section: the margin and the probe by hand on made-up samples, the DP shares, and the section drawn
from tiny runs (claims, Fig. 8.2's paths, the hidden-state figure, the story picture, the 8.5 table)."""

import numpy as np
import pytest

from connrl.report import integration as ri
from connrl.report import integration_probe as rp
from tests.tiny_runs import run_tiny


def test_margin_by_hand():
    d, two_se = ri.margin([0.6, 0.8, 0.7], [0.1, 0.1, 0.1])
    assert d == pytest.approx(0.6) and two_se == pytest.approx(2 * np.sqrt(0.01 / 3))


def _samples(rng, n_trials, separable):
    out = []
    for t in range(n_trials):
        door = "AB"[t % 2]
        for _ in range(5):
            ctx = rng.normal(0, 1, 8)
            if separable:
                ctx[3] += 3.0 if door == "A" else -3.0  # one context unit carries the doorway
            out.append({"door": door, "trial": t, "start_room": "B", "behaviour": 1 if door == "A" else 2,
                        "x": rng.normal(0, 1, 14).tolist(), "q": [0, 0, 0, 0], "context": ctx.tolist()})
    return out


def test_probe_tells_the_doorways_apart_only_when_the_features_carry_them():
    rng = np.random.default_rng(0)
    s = _samples(rng, 40, separable=True)
    assert rp.probe_accuracy(s, "context") > 0.95 and rp.probe_accuracy(s, "both") > 0.9
    assert 0.3 < rp.probe_accuracy(s, "inputs") < 0.7  # the inputs are noise here: chance
    assert rp.probe_accuracy(s[:5], "inputs") is None  # one trial: nothing held out
    assert rp.dp_share(s, "A") == 1.0 and rp.dp_share(s, "B") == 0.0 and rp.dp_share(s, "B", "A") is None


def test_chapter_8_section_from_tiny_runs(tmp_path):
    for name in ("integration", "steps-to-learn"):
        run_tiny(name, tmp_path)
    doc = tmp_path / "docs" / "RESULTS.md"
    md = ri.results_section(tmp_path, doc)
    for heading in ("### The claims of 8.2-8.4 beside ours", "### integration:", "### The hidden state made visible",
                    "### The 8.5 table: steps to learn each task", "### steps-to-learn:"):
        assert heading in md
    for row in ("| DK | 100 |", "| DP | 100 |", "| WFL | 150 |", "| WFR | 150 |", "| CHG (no X-Y, recurrent-Q) | 0 |"):
        assert row in md
    for fig in ("integration-changed-paths", "integration-hidden-state", "robot-story"):
        assert (doc.parent / "figures" / f"{fig}.png").exists()


def test_solution_paths_take_per_room_the_first_docked_run():
    def rec(seed, docked, label=ri.RECURRENT):
        paths = [{"room": r, "success": ok, "poses": [[0, 0, 0]], "behaviours": []}
                 for r, ok in zip("ABC", docked, strict=True)]
        return {"seed": seed, "variant": label, "extra": {"changed_paths": paths}}

    records = [rec(1, (False, True, False)), rec(0, (True, False, False)), rec(2, (True, True, True), ri.CH6)]
    picked = ri.solution_paths(records, ri.RECURRENT)
    assert [(p["room"], p["seed"], p["success"]) for p in picked] == [("A", 0, True), ("B", 1, True), ("C", 0, False)]
