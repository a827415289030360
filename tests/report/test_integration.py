"""Ch. 8's results section: the margin and the probe by hand on made-up samples, the DP shares, and the section drawn
from tiny runs (claims, Fig. 8.2's paths, the hidden-state figure, the story picture, the 8.5 table)."""

import numpy as np

from connrl.report import integration as ri
from connrl.report import integration_probe as rp
from tests.tiny_runs import run_tiny


def _curve(perfs, steps_per_test=100.0):
    return [{"trials": 10.0 * k, "performance": p, "train_steps": steps_per_test * k} for k, p in enumerate(perfs)]


def test_good_is_a_fixed_level_so_an_early_plateau_does_not_count():
    from connrl.experiments.steps import run_steps_to_level, steps_to_good, steps_to_level

    plateau = [_curve([0.0, 0.35, 0.36, 0.36, 0.36, 0.36]) for _ in range(3)]
    assert steps_to_good(plateau) == (10.0, 100.0)  # the old rule: 90 % of its own final level at trial 10
    assert steps_to_level(plateau, 1.0) == (None, None)  # half a teacher of 2.0: never reached
    rising = [_curve([0.0, 0.4, 0.8, 1.1, 1.3, 1.4]) for _ in range(3)]
    assert steps_to_level(rising, 1.0) == (30.0, 300.0) and run_steps_to_level(rising[0], 1.0) == 300.0
    row = ri.StepsRow("DK", 100, 102.0, 2000, 1.0, *steps_to_level(plateau, 1.0), [None] * 3, 50.0, 0.18)
    assert ri.step_verdict(row)[0] == ri.NOT_REPRODUCED
    ok = ri.StepsRow("DK", 100, 102.0, 2000, 1.0, 30.0, 2100.0, [2000.0, 2100.0, 2200.0], 300.0, 0.7)
    assert ri.step_verdict(ok)[0] == ri.REPRODUCED  # at most 1.5 x 2,000
    table = ri.steps_table([ok, row])
    assert "not reached in 50 trials" in table[3] and table[-1].startswith("| **total**") and "— (a row" in table[-1]


def test_chapter_8_claims_use_the_verdict_rules():
    q = {"final_docked_B": {"per_run": [0.11, 0.2, 0.05, 0.1]}, "final_performance": {"per_run": [0.3, 0.35, 0.4, 0.3]}}
    summary = {"variants": {ri.RECURRENT: {"quantities": q},
                            ri.MEMORYLESS: {"quantities": {"final_docked_B": {"per_run": [0.04, 0.0, 0.1, 0.02]}}},
                            ri.CH6: {"quantities": {"final_performance": {"per_run": [0.7, 0.72, 0.69, 0.71]}}}}}
    found = {c.claim: c for c in ri.checks(summary)}
    assert found["without X-Y the memoryless robot generally fails from room B"].verdict == ri.REPRODUCED
    assert found["recurrent-Q acceptably good after 150 trials"].verdict == ri.NOT_REPRODUCED


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


def test_the_memory_table_compares_the_right_learners_per_entry_into_room_c():
    from connrl.experiments import integration

    spec = {v.label: v.params for v in integration.EXPERIMENTS[0].variants}
    rec = spec[ri.RECURRENT]
    assert rec["memory"] == "recurrent" and rec["context"] > 0
    assert spec[ri.SAME_REPLAYS] == {"lessons_per_trial": rec["lessons_per_trial"]}  # memoryless, the same replays
    assert spec[ri.NO_CONTEXT] == {**rec, "context": 0}
    assert spec[ri.MEMORYLESS] == {} and "xy" not in rec

    def runs(b, returns, reached):
        return {"quantities": {"final_docked_B": {"per_run": b}, "final_performance": {"per_run": [0.5, 0.6, 0.7]},
                               "default_B_returns": {"per_run": returns}, "default_B_reached_C": {"per_run": reached}}}

    summary = {"variants": {ri.RECURRENT: runs([0.6, 0.7, 0.8], [0.5, 0.5, 0.5], [1.0, 1.0, 1.0]),
                            # never leaving B gives 0 passes back per test; per entry into C it has no value
                            ri.SAME_REPLAYS: runs([0.0, 0.05, 0.1], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
                            ri.NO_CONTEXT: runs([0.2, 0.3, 0.25], [2.0, 2.5, 1.5], [1.0, 1.0, 0.5])}}
    table = ri.memory_table(summary)
    same, none = table[2], table[3]
    assert "better? yes" in same.split("|")[2] and same.split("|")[4].strip() == "—"
    assert "0.50 vs 2.50, better? yes" in none.split("|")[4]  # 2.0, 2.5 and 1.5 / 0.5 = 3 per entry


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
    for row in ("| DK | 100 |", "| DP | 100 |", "| WFL | 150 |", "| WFR | 150 |",
                "| CHG (no X-Y, recurrent-Q, ours) | 0 |",
                "| CHG (no X-Y, recurrent-Q at 8.3's lr 0.08, 100 lessons) | 0 |"):
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
