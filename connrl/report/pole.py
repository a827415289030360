"""docs/RESULTS.md section for pole balancing with memoryless agents (7.5.4 fn. 4): ``connrl.experiments.pole``."""

from __future__ import annotations

from pathlib import Path

from connrl.experiments.pole import EXPERIMENTS
from connrl.report import checks
from connrl.report.page import figure, load_summary, note, summary_table


def results_section(out_dir, doc=Path("docs/RESULTS.md")) -> str:
    """The stored summaries of pole-full and pole-full-ahc, with how to read them."""
    out_dir, doc = Path(out_dir), Path(doc)
    parts = ["## Pole balancing, full state (thesis 7.5.4, footnote 4; App. C)", "", note("pole-intro"), ""]
    for spec in EXPERIMENTS:
        summary = load_summary(out_dir, spec.name)
        if summary is None:
            continue
        checks.meets_claims(summary, "7.5.4 fn. 4", "7.5.4", f"{spec.name}: {spec.title}")
        parts += [f"### {spec.name}: {spec.title}", "", summary_table(summary), "",
                  figure(out_dir / spec.name / "curve.png", doc, spec.name), ""]
    parts += [note("pole-choices"), ""]
    return "\n".join(parts)
