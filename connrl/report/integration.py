"""docs/RESULTS.md section for Ch. 8 (integration): the claims of 8.2-8.4 beside the stored ``integration`` runs, Fig.
8.1's curves (overall and per start room), the changed environment (Fig. 8.2), the hidden state made visible, the
8.5 table (with ``steps-to-learn``) and the whole robot story in one picture (``docs/figures/robot-story.png``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from connrl.envs.robot.recharge import ROOMS
from connrl.experiments import integration, steps
from connrl.experiments.steps import GOOD_FRACTION, THESIS_CHG_WITH_XY, THESIS_STEPS, steps_to_good
from connrl.report.integration_probe import draw_probe, probe_table
from connrl.report.page import figure, load_summary, note, run_rows, stored, summary_table
from connrl.report.recharge import draw_room_curves
from connrl.report.recharge_claims import at_end, draw_paths, quantity
from connrl.report.story import draw_story

EXPERIMENTS = [*integration.EXPERIMENTS, *steps.EXPERIMENTS]
CH6, MEMORYLESS, RECURRENT, RECURRENT_XY, RECURRENT_SLOW = (v.label for v in integration.EXPERIMENTS[0].variants)
ACCEPTABLE = 0.8  # "acceptably good" read as: at least 80 % of Ch. 6 Exp. 3's final performance (with X-Y) (R)


def _f(v, digits=2) -> str:
    return "—" if v is None else f"{v:,.{digits}f}"


def margin(a: list[float], b: list[float]) -> tuple[float, float]:
    """Difference of means ``mean(a) - mean(b)`` and twice its standard error (Welch); "clearly beats" when the
    difference exceeds it, i.e. beyond the run-to-run spread of both."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    se = np.sqrt((a.var(ddof=1) / len(a) if len(a) > 1 else 0.0) + (b.var(ddof=1) / len(b) if len(b) > 1 else 0.0))
    return float(a.mean() - b.mean()), float(2 * se)


def per_run(summary: dict, label: str, name: str) -> list[float]:
    vals = summary["variants"].get(label, {}).get("quantities", {}).get(name, {}).get("per_run") or []
    return [v for v in vals if v is not None]


def _mean(vals) -> float | None:
    return float(np.mean(vals)) if vals else None


def claims(summary: dict) -> list[str]:
    rec_b, mem_b = per_run(summary, RECURRENT, "final_docked_B"), per_run(summary, MEMORYLESS, "final_docked_B")
    rec, ch6 = per_run(summary, RECURRENT, "final_performance"), per_run(summary, CH6, "final_performance")
    lines = ["| claim (thesis) | criterion | ours | holds? |", "|---|---|---|---|"]
    if len(rec_b) > 1 and len(mem_b) > 1:  # a spread needs 2 runs a side
        d, m2 = margin(rec_b, mem_b)
        lines.append(f"| from room B, recurrent-Q clearly beats memoryless (8.3) | share of room-B test tasks docked, "
                     f"last 3 tests: difference of means above twice its standard error | recurrent {_mean(rec_b):.2f}"
                     f", memoryless {_mean(mem_b):.2f}: difference {d:+.2f}, 2 SE {m2:.2f} | "
                     f"{'yes' if d > m2 else 'no'} |")
        lines.append(f"| memoryless generally fails from room B (8.2) | below half of room-B tasks docked | "
                     f"{_mean(mem_b):.2f} | {'yes' if _mean(mem_b) < 0.5 else 'no'} |")
    if rec and ch6:
        ratio = _mean(rec) / _mean(ch6) if _mean(ch6) else None
        lines.append(f"| acceptably good after 150 trials (8.3) | final performance at least {ACCEPTABLE:.0%} of Ch. 6 "
                     f"Exp. 3's (with X-Y, same seeds) | {_mean(rec):.2f} vs {_mean(ch6):.2f} ({_f(ratio)}) | "
                     f"{'yes' if ratio is not None and ratio >= ACCEPTABLE else 'no'} |")
    changed = [quantity(summary, RECURRENT, f"changed_docked_{r}") for r in ROOMS]
    if all(c is not None for c in changed):
        lines.append(f"| in the changed layout the recurrent policy still docks, learning off (8.4) | docks from "
                     f"most (> 50 %) fresh tasks of each room | A {changed[0]:.2f}, B {changed[1]:.2f}, C "
                     f"{changed[2]:.2f} | {'yes' if min(changed) > 0.5 else 'no'} |")
    return lines


def layouts_table(summary: dict) -> list[str]:
    """Exp. 3: per learner and start room, docked share and steps, original and changed layout (mean over runs)."""
    lines = ["| learner | room | docked, original | docked, changed | steps, original | steps, changed |",
             "|---|---|---|---|---|---|"]
    for label in summary["variants"]:
        for r in ROOMS:
            cells = [_f(quantity(summary, label, f"{lay}_{what}_{r}"), 2 if what == "docked" else 0)
                     for what in ("docked", "steps") for lay in ("default", "changed")]
            lines.append(f"| {label} | {r} | " + " | ".join(cells) + " |")
    return lines


def legs_table(summary: dict) -> list[str]:
    """Where room B's final tests fail, per learner (original layout, mean over runs)."""
    lines = ["| learner | reach room C | reach room A | docked | passes from C back into B per task |",
             "|---|---|---|---|---|"]
    for label in summary["variants"]:
        cells = [_f(quantity(summary, label, f"default_{key}")) for key in
                 ("B_reached_C", "B_reached_A", "docked_B", "B_returns")]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return lines


def steps_table(chg: tuple | None, beh: tuple | None) -> list[str]:
    """The 8.5 table: teaching steps, then experimental steps to a good policy (one definition for every row)."""
    lines = ["| task | teaching steps, thesis | ours | experimental steps to a good policy, thesis | ours (trials) | "
             "final level / scripted teacher's |", "|---|---|---|---|---|---|"]
    rows = []
    if beh is not None:
        spec, summary, out = beh
        for v in spec.variants:
            task = v.params["task"]
            runs = run_rows(spec, summary, out, v.label)
            trials, spent = steps_to_good(runs)
            teach = quantity(summary, v.label, "teaching_steps")
            ratio = _ratio(at_end(runs, "performance"), quantity(summary, v.label, "teacher_performance"))
            rows.append((task, THESIS_STEPS[task][0], teach, THESIS_STEPS[task][1], spent, trials, ratio))
    if chg is not None:
        spec, summary, out = chg
        for label, task, thesis in ((RECURRENT, "CHG (no X-Y, recurrent-Q)", THESIS_STEPS["CHG"][1]),
                                    (CH6, "CHG with X-Y (Ch. 6 Exp. 3; 8.5 fn. 1)", THESIS_CHG_WITH_XY)):
            runs = run_rows(spec, summary, out, label)
            trials, spent = steps_to_good(runs)
            ratio = _ratio(at_end(runs, "performance"), quantity(summary, label, "teacher_performance"))
            rows.append((task, 0, 0, thesis, spent, trials, ratio))
    for task, t_th, t_ours, e_th, e_ours, trials, ratio in rows:
        lines.append(f"| {task} | {t_th:,} | {_f(t_ours, 0)} | {e_th:,} | {_f(e_ours, 0)} ({_f(trials, 0)}) | "
                     f"{_f(ratio)} |")
    return lines


def solution_paths(records: list[dict], label: str) -> list[dict]:
    """Per start room, the changed-layout path of the first run (by seed) of ``label`` whose path from that room
    docked, else the first run's; each tagged with its run's seed."""
    runs = [r for r in sorted(records, key=lambda r: r["seed"]) if r["variant"] == label
            and r.get("extra", {}).get("changed_paths")]
    out = []
    for room in ROOMS:
        paths = [{**p, "seed": r["seed"]} for r in runs for p in r["extra"]["changed_paths"] if p["room"] == room]
        if paths:
            out.append(next((p for p in paths if p["success"]), paths[0]))
    return out


def _core(summary: dict) -> dict:
    """The summary with the training curve's quantities only (the final tests have tables of their own)."""
    keep = {q.name for q in integration.QUANTITIES}
    return {**summary, "variants": {label: {**v, "quantities": {k: q for k, q in v["quantities"].items() if k in keep}}
                                    for label, v in summary["variants"].items()}}


def _ratio(a, b):
    return a / b if a is not None and b else None


def hidden_state_lines(summary: dict, records: list[dict], folder: Path, doc: Path) -> list[str]:
    """The doorway probe's table and figure (``connrl.report.integration_probe``)."""
    by_label = {label: [r["extra"].get("probe", []) for r in records if r["variant"] == label]
                for label in summary["variants"]}
    lines = ["### The hidden state made visible", "",
             "The steps of the final greedy tests (original layout) taken in room C within 30 in of subgoal 4 "
             "(in front of door A) or 5 (door B), at most 300 per run (a random subsample). DP is right at door "
             "A; at door B it takes a robot that came from room B straight back. The probe is a linear "
             "classifier of the doorway fitted within each run and scored on held-out trials (chance 0.5; "
             "connrl.report.integration_probe):", "", *probe_table(by_label), ""]
    png = draw_probe(by_label, RECURRENT, folder / "hidden-state.png")
    return lines + ([figure(png, doc, "integration-hidden-state"), ""] if png is not None else [])


def results_section(out_dir, doc=Path("docs/RESULTS.md")) -> str:
    out_dir, doc = Path(out_dir), Path(doc)
    spec, beh_spec = integration.EXPERIMENTS[0], steps.EXPERIMENTS[0]
    (summary, records), beh_summary = stored(spec, out_dir), load_summary(out_dir, beh_spec.name)
    if summary is None and beh_summary is None:
        return ""
    lines = ["## Chapter 8: integration -- recharging without X-Y (Figs. 8.1, 8.2, the 8.5 table)", ""]
    if summary is not None:
        lines += ["### The claims of 8.2-8.4 beside ours", "", *claims(summary), "",
                  f"### {spec.name}: {spec.title} (thesis {spec.section})", "", summary_table(_core(summary)), "",
                  "The final tests' quantities (per room, both layouts) are in the tables below and in "
                  f"`runs/{spec.name}/summary.json` (`connrl show {spec.name}`).", "",
                  "Fig. 8.1 (mean over runs; the Ch. 6 Exp. 3 curve is run here on the same seeds, as the thesis shows "
                  "it beside the two):", "", figure(out_dir / spec.name / "curve.png", doc, spec.name), ""]
        rooms = draw_room_curves(spec, summary, out_dir, out_dir / spec.name / "rooms.png")
        if rooms is not None:
            lines += ["By start room (mean over runs):", "", figure(rooms, doc, f"{spec.name}-rooms"), ""]
        lines += ["Experiment 3 (8.4): each run's final policy, learning off, on fresh tasks in the original and in "
                  "the changed layout (docs/RECONSTRUCTION.md, \"Changed environment\"); steps are the primitive steps "
                  "of the docked tasks (mean over runs):", "", *layouts_table(summary), ""]
        lines += ["Where room B's tests fail (the same final tests, original layout; mean over runs):", "",
                  *legs_table(summary), ""]
        picked = solution_paths(records, RECURRENT)
        if picked:
            png = draw_paths({"extra": {"changed_paths": picked}}, out_dir / spec.name / "changed-paths.png",
                             "Exp. 2 in the changed layout, learning off", key="changed_paths", layout="changed")
            seeds = ", ".join(f"{p['room']}: seed {p['seed']}" for p in picked)
            lines += ["Fig. 8.2: a solution path in the changed layout from each room by the recurrent policies: per "
                      "room, the first run (by seed) whose first final test from that room docked, else the first "
                      f"run's path ({seeds}):", "",
                      figure(png, doc, f"{spec.name}-changed-paths"), ""]
        lines += hidden_state_lines(summary, records, out_dir / spec.name, doc)
        story = draw_story(records, CH6, RECURRENT, out_dir / spec.name / "story.png")
        if story is not None:
            lines += ["The robot story in one picture (README): behaviours, the hierarchy over them, and a recurrent "
                      "policy without X-Y docking from room B:", "", figure(story, doc, "robot-story"), ""]
    lines += ["### The 8.5 table: steps to learn each task", "",
              f"A good policy, for every row: the first test at which the mean curve over runs has come "
              f"{GOOD_FRACTION:.0%} of the way from its first test to its final level (mean of its last 3 tests). "
              "Experimental steps are the primitive actions of the learning trials before that test (mean over runs); "
              "teaching steps those of the taught lessons. The last column says how good that final level is: "
              "reinforcement per step over the scripted teacher's on the same tasks.", "",
              *steps_table((spec, summary, out_dir) if summary is not None else None,
                           (beh_spec, beh_summary, out_dir) if beh_summary is not None else None), ""]
    if beh_summary is not None:
        lines += [f"### {beh_spec.name}: {beh_spec.title} (thesis {beh_spec.section})", "", summary_table(beh_summary),
                  "", figure(out_dir / beh_spec.name / "curve.png", doc, beh_spec.name), ""]
    lines += [note("integration"), ""]
    return "\n".join(lines)
