"""The 4.5 speedup table (Study 2 Q-agents, plays to 8 food per play) and the helpers the Ch. 4 sections share.

``speedup`` reads the table off an experiment's mean curves: the stored Study 2 runs (seeds 0-6, criterion: within
the thesis's plays) or the fresh-seed runs of issue 31's check (criterion: within 1.5x the thesis's plays).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from connrl.experiments.survival import EXPERIMENTS
from connrl.report import checks, verdicts
from connrl.report.page import figure, stored
from connrl.report.wall import copies_text, run_seconds, wall_text

SPECS = {s.name: s for s in EXPERIMENTS}
SPEEDUP_ROWS = [("QCON", "no extensions", 200), ("QCON-M (learned model)", "using a learned model", 140),
                ("QCON-M (perfect model)", "using a perfect model", 95), ("QCON-R", "experience replay", 80),
                ("QCON-T", "experience replay + teaching", 60)]


def load_records(out: Path, name: str) -> tuple[dict | None, list[dict]]:
    return stored(SPECS[name], out)


def crossing(xs, ys, level: float) -> float | None:
    """First x at which the piecewise-linear curve (xs, ys) reaches ``level`` (None if never)."""
    for i, (x, y) in enumerate(zip(xs, ys, strict=True)):
        if y >= level:
            if i == 0:
                return float(x)
            x0, y0 = xs[i - 1], ys[i - 1]
            return float(x0 + (level - y0) * (x - x0) / (y - y0))
    return None


def mean_curve(recs: list[dict]) -> tuple[list[float], list[float]]:
    n = min(len(r["curve_x"]) for r in recs)
    return recs[0]["curve_x"][:n], list(np.mean(np.array([r["curve_y"][:n] for r in recs], dtype=float), axis=0))


def command(summary: dict) -> str:
    n, s = summary["runs_per_variant"], summary["base_seed"]
    return (f"`connrl run {summary['experiment']} --profile {summary['profile']} --runs {n} --seed {s}` "
            f"({n} run(s) per agent, seeds {s}..{s + n - 1}, {wall_text(summary, 'min')}, "
            f"{sum(run_seconds(summary)) / 60:.1f} min of run time{copies_text(summary)})")


def by_variant(recs: list[dict]) -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = {}
    for r in sorted(recs, key=lambda r: r["seed"]):
        out.setdefault(r["variant"], []).append(r)
    return out


def _table(byv: dict, factor: float) -> tuple[list[str], dict]:
    lines = ["| agent | thesis plays | thesis speedup | our plays (mean curve) | our speedup | per-run plays | runs |",
             "|---|---|---|---|---|---|---|"]
    base, ours = None, {}
    for label, text, t in SPEEDUP_ROWS:
        rs = byv.get(label, [])
        if not rs:
            continue
        c8 = crossing(*mean_curve(rs), 8.0)
        ours[label] = c8
        if label == "QCON":
            base = c8
        per = ", ".join("—" if r["metrics"]["plays_to_8"] is None else f"{r['metrics']['plays_to_8']:.0f}" for r in rs)
        sp = f"{base / c8:.1f}" if base and c8 else "—"
        lines.append(f"| {text} | {t:g}{f' (×{factor:g}: {t * factor:g})' if factor != 1 else ''} | {200 / t:.1f} | "
                     f"{'not reached' if c8 is None else f'{c8:.0f}'} | {sp} | {per} | {len(rs)} |")
    return lines, ours


def plays_verdict(ours: dict[str, float | None], factor: float = 1.0) -> str:
    """Reproduced when every agent's mean curve reaches 8 within ``factor`` x the thesis's plays; partly: some do."""
    thesis = {lab: t for lab, _, t in SPEEDUP_ROWS}
    within = [lab for lab, c8 in ours.items() if c8 is not None and c8 <= thesis[lab] * factor]
    return verdicts.REPRODUCED if len(within) == len(ours) else verdicts.PARTLY if within else verdicts.NOT_REPRODUCED


def speedup(out: Path, doc: Path, name: str = "survival-speedup", tag: str = "", factor: float = 1.0,
            cause: str = "") -> list[str]:
    """The table, its ordering check and two scoreboard claims; ``tag`` tells a second copy's headings apart;
    ``cause`` (the measured cause of a gap) goes with a plays-to-8 verdict short of reproduced."""
    summary, recs = load_records(out, name)
    source = name
    if summary is None and name == "survival-speedup":
        source = "survival-study2"
        summary, recs = load_records(out, source)
    if summary is None:
        return []
    byv = by_variant(recs)
    heading = f"Table of 4.5: Study 2 Q-agents, plays to reach 8 food per play{tag}"
    table, ours = _table(byv, factor)
    lines = [f"### {heading}", "", command(summary) + (" (read from Study 2's runs)" if source != name else ""), "",
             *table]
    expected = [lab for lab, _, _ in reversed(SPEEDUP_ROWS) if lab in byv]  # fastest first, as the table says
    word, pair_lines = checks.ordering_check(
        {lab: [r["metrics"]["food_auc"] for r in byv[lab]] for lab in expected}, expected)
    lines += ["", "A run that never reaches 8 within 300 plays is shown as —.", "",
              "**Ordering check.** The table orders the agents, fastest first: " + " > ".join(expected) + ". Plays to "
              "8 cannot order runs that never reach 8 within the 300 plays, so each pair is checked on the mean food "
              "over all tests (our measure of speed), one-sided Welch t-test at 0.05 per adjacent pair "
              "(`verdicts.ordering`); the whole ordering is reproduced only when every pair is in order:", "",
              *[f"- {line}" for line in pair_lines], "", f"Ordering: **{word}**.", ""]
    means = {lab: float(np.mean([r["metrics"]["food_auc"] for r in byv[lab]])) for lab in expected}
    verdicts.claim(f"Table 4.5: the ordering of the speedups{tag}", "4.5", " > ".join(expected) + " (fastest first)",
                   "food over all tests " + ", ".join(f"{lab} {m:.2f}" for lab, m in means.items()),
                   "each adjacent pair in order, one-sided Welch at 0.05 on food over all tests",
                   checks.ordering_verdict(word), anchor=heading, recheck=bool(tag))
    # the re-check repeats the check's own rule (the thesis's plays), so it never stands in for the check under an
    # easier one; issue 31's looser factor is said in the section, not scored a second time on the same cells
    verdict = plays_verdict(ours, 1)
    verdicts.claim(f"Table 4.5: plays to reach 8{tag}", "4.5", ", ".join(f"{lab} {t}" for lab, _, t in SPEEDUP_ROWS),
                   ", ".join(f"{lab} {'not reached' if ours[lab] is None else f'{ours[lab]:.0f}'}" for lab in ours),
                   "the mean curve reaches 8 within the thesis's plays, every agent (no test of spread)",
                   verdict, "" if verdict == verdicts.REPRODUCED else cause, anchor=heading, recheck=bool(tag))
    if factor != 1:
        lines += [f"Within {factor:g}× the thesis's plays (issue 31's looser criterion, shown, not scored a second "
                  f"time): **{plays_verdict(ours, factor)}**.", ""]
    if source == "survival-speedup":  # elsewhere the study's own section shows the curves
        lines += [figure(out / source / "curve.png", doc, source), ""]
    return lines
