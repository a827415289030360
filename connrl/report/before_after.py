"""Before and after issue 44's world: every Ch. 5, 6 and 8 summary row (experiment, variant, quantity) in the world
before it (the summaries kept in ``OUT/../before-44``) beside the same row now (``OUT``)."""

from __future__ import annotations

from pathlib import Path

from connrl.experiments.registry import by_chapter
from connrl.report.page import load_summary

EXPERIMENTS = ()  # reads the other sections' summaries
BEFORE = "before-44"


def _cell(q: dict | None, runs: int) -> str:
    if q is None:
        return "-"
    mean = q.get("mean")
    text = "-" if mean is None else f"{mean:.3g}"
    if q["description"].startswith("trials until") and q.get("runs_reaching") is not None:
        text += f" ({q['runs_reaching']}/{runs})"
    return text


def _rows(name: str, before: dict | None, after: dict | None) -> list[str]:
    """One table row per (variant, quantity) of either summary."""
    bv, av = (before or {}).get("variants", {}), (after or {}).get("variants", {})
    rows = []
    for label in dict.fromkeys([*av, *bv]):
        b, a = bv.get(label, {}), av.get(label, {})
        bq, aq = b.get("quantities", {}), a.get("quantities", {})
        for q in dict.fromkeys([*aq, *bq]):
            thesis = (aq.get(q) or bq.get(q) or {}).get("thesis")
            rows.append(f"| {name} | {label} | {q} | {'' if thesis is None else thesis} | "
                        f"{_cell(bq.get(q), len(b.get('seeds', [])))} | {_cell(aq.get(q), len(a.get('seeds', [])))} |")
    return rows


def results_section(out: Path, doc: Path) -> str:
    before_dir = out.parent / BEFORE
    if not before_dir.is_dir():
        return ""
    lines = ["## Before and after the world of issue 44", "",
             f"Every summary row of the Ch. 5, 6 and 8 experiments: the mean over runs in the world before issue 44 "
             f"(`{before_dir}`, the summaries the page showed before; full profile, the same seeds and commands) and "
             f"now (`{out}`), with the thesis's value where a row has one. Trials-to rows give the runs that reached "
             "the level. The pre-issue-44 experiments `robot-dp-calibration` and `robot-dp-geometry` pin that world "
             "and should not move; `robot-dp-fresh` moved to the fresh seeds 6000-6006.", ""]
    for chapter in (5, 6, 8):
        rows = [row for spec in by_chapter([chapter])
                for row in _rows(spec.name, load_summary(before_dir, spec.name), load_summary(out, spec.name))]
        if rows:
            lines += [f"<details><summary>Chapter {chapter}: {len(rows)} rows</summary>", "",
                      "| experiment | variant | quantity | thesis | before | after |", "|---|---|---|---|---|---|",
                      *rows, "", "</details>", ""]
    return "\n".join(lines)
