"""docs/RESULTS.md section for 6.2's complexity analysis (``connrl run complexity``): executions against n on log-log
axes per dimension and exploration rule, the thesis's formulas drawn beside, and the fitted exponents beside Table
6.1's orders."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from connrl.experiments.complexity import EXPERIMENTS, LEARNERS
from connrl.report.page import figure, fixed, note, run_rows, stored
from connrl.report.plots import save_figure
from connrl.report.wall import wall_text

THESIS = {  # Table 6.1 and 6.2.2-6.2.3: the order in n, per dimension
    1: {"flat": "2", "single": "1.5", "multi": "n log n", "additional_inside": "1.5", "additional_outside": "1.5"},
    2: {"flat": "2", "single": "1.4 (55 n^1.4)", "multi": "1 (1728 n)", "additional_inside": "1.4 (22 n^1.4)",
        "additional_outside": "1.4 (4 n^0.8 + 22 n^1.4)"},
}
FORMULAS = {2: {"flat": lambda n: 4.0 * n ** 2, "single": lambda n: 55.0 * n ** 1.4, "multi": lambda n: 1728.0 * n}}
STYLE = {"flat": "C0", "single": "C1", "multi": "C2", "additional_inside": "C3", "additional_outside": "C4"}


def draw(rows: dict[str, list[list[dict]]], dims: dict[str, int], file: Path) -> Path:
    """One panel per variant: each learner's mean executions over runs against n; the thesis's 2-D formulas
    (flat b n = 4 n^2, single level 55 n^1.4, multi-level 1728 n) dashed."""
    fig, axes = plt.subplots(1, len(rows), figsize=(4.2 * len(rows), 3.8), dpi=110, squeeze=False)
    for ax, (label, runs) in zip(axes[0], rows.items(), strict=True):
        ns = np.array([row["n"] for row in runs[0]], dtype=float)
        for name in LEARNERS:
            ys = np.mean([[row.get(name, np.nan) for row in run] for run in runs], axis=0)
            ok = np.isfinite(ys) & (ys > 0)
            ax.loglog(ns[ok], ys[ok], "o-", color=STYLE[name], ms=3, label=name.replace("_", " "))
        dim = dims[label]
        for name, f in FORMULAS.get(dim, {}).items():
            ax.loglog(ns, f(ns), "--", color=STYLE[name], lw=0.8)
        ax.set_title(f"{label} ({len(runs)} runs)", fontsize=9)
        ax.set_xlabel("states n")
        ax.grid(alpha=0.3, which="both")
    axes[0][0].set_ylabel("action executions")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, file)
    plt.close(fig)
    return file


def _constant(records, label, name) -> str:
    cs = [r["metrics"].get(f"constant_{name}") for r in records if r["variant"] == label]
    cs = [c for c in cs if c is not None]
    return f"{np.mean(cs):.3g}" if cs else "—"


def results_section(out_dir: Path, doc: Path = Path("docs/RESULTS.md")) -> str:
    out_dir = Path(out_dir)
    spec = EXPERIMENTS[0]
    summary, records = stored(spec, out_dir)
    if summary is None or not records:
        return ""
    t = summary.get("timing", {}).get("wall_time_s")
    wall = wall_text(summary) if t is not None else f"wall time {fixed(t, 0)}"
    lines = ["## Section 6.2: the complexity of learning, flat and hierarchical (Table 6.1)", "",
             f"`connrl run complexity --profile {summary['profile']} --runs {summary['runs_per_variant']} --seed "
             f"{summary['base_seed']}`: {summary['runs_per_variant']} runs per variant (seeds from "
             f"{summary['base_seed']}), {wall}. The thesis derived these orders and measured none "
             "of them.", "",
             "Fitted exponents e and constants c of executions ~ c n^e (means over runs), beside Table 6.1:", "",
             "| variant | " + " | ".join(n.replace("_", " ") for n in LEARNERS) + " |",
             "|---|" + "---|" * len(LEARNERS)]
    dims = {r["variant"]: int(r["params"]["dim"]) for r in records}
    rows = {label: run_rows(spec, summary, out_dir, label) for label in summary["variants"]}
    rows = {k: v for k, v in rows.items() if v}
    for label, v in summary["variants"].items():
        cells = [f"{fixed(v['quantities'][f'exponent_{n}']['mean'])}, c = {_constant(records, label, n)} (thesis "
                 f"{THESIS[dims[label]][n]})" for n in LEARNERS]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    lines += ["", "Regions that were cheapest at each size, beside the thesis's optimal k (its formula; first run), "
              "and the single level's paths through subgoals against the shortest (BFS):", "",
              "| variant | n | cheapest k | thesis's k | single level at the thesis's k / at the cheapest | path / "
              "shortest |", "|---|---|---|---|---|---|"]
    for label, runs in rows.items():
        for row in runs[0]:
            n = int(row["n"])
            thesis_k = round((7.8 * n ** 0.6) if dims[label] == 2 else 4 * n ** 0.5)
            ratio = row["single_at_thesis_k"] / row["single"] if row.get("single_at_thesis_k") else None
            lines.append(f"| {label} | {n} | {int(row['best_k'])} | {thesis_k} | {fixed(ratio)} | "
                         f"{fixed(row.get('overhead_single'), 3)} |")
    png = draw(rows, dims, out_dir / spec.name / "executions.png")
    lines += ["", figure(png, doc, "complexity-executions"), "", note("complexity"), ""]
    return "\n".join(lines)
