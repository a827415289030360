"""docs/RESULTS.md part for Fig. 5.2 (``connrl run td-depth``): D measured from the code's lambda-returns beside the
thesis's D = -1/ln(lambda), as a figure and a table with a verdict."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt

from connrl.experiments.td_depth import EXPERIMENTS, MARKS
from connrl.report import verdicts
from connrl.report.page import figure, fixed, run_rows, stored
from connrl.report.plots import save_figure
from connrl.report.wall import wall_text

MATCH = 1e-6  # relative deviation from the formula below which D counts as reproduced (float rounding only)


def draw_depth(rows: list[dict], file: Path) -> Path:
    """Fig. 5.2 redrawn: measured D (points) on the thesis's curve, and the weights' mean look-ahead."""
    lams = [r["lam"] for r in rows]
    fine = [i / 1000 for i in range(20, 991)]
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    ax.plot(fine, [-1 / math.log(x) for x in fine], color="k", lw=1.2, label="thesis: D = -1/ln(lambda)")
    ax.plot(lams, [r["depth"] for r in rows], "o", color="C0", ms=4, label="D measured: weight falls to 1/e")
    ax.plot(lams, [r["mean_lookahead"] for r in rows], "s", color="C1", ms=3, mfc="none",
            label="mean look-ahead of the weights")
    ax.set_xlabel("lambda")
    ax.set_ylabel("steps")
    ax.set_xlim(0, 1)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title("Fig. 5.2: D against lambda, from connrl.core.returns.lambda_returns", fontsize=9)
    fig.tight_layout()
    save_figure(fig, file)
    plt.close(fig)
    return file


def results_section(out_dir: Path, doc: Path = Path("docs/RESULTS.md")) -> str:
    spec = EXPERIMENTS[0]
    summary, recs = stored(spec, Path(out_dir))
    runs = run_rows(spec, summary, Path(out_dir), spec.variants[0].label) if summary is not None else []
    if not recs or not runs:
        return ""  # the page lists it under "Not yet run"
    rows = runs[0]  # one deterministic run: a row per lambda
    dev = summary["variants"][spec.variants[0].label]["quantities"]["max_rel_deviation"]["mean"]
    ok = dev is not None and dev < MATCH
    by_lam = {r["lam"]: r for r in rows}
    verdicts.claim("Fig. 5.2: D = -1/ln(lambda)", "5.1.1", "D = -1/ln(lambda)",
                   f"largest relative deviation {dev:.1e}" if dev is not None else "—",
                   f"every lambda's D within {MATCH:g} of the formula (deterministic)",
                   verdicts.REPRODUCED if ok else verdicts.NOT_REPRODUCED,
                   anchor=f"{spec.name}: {spec.title} (thesis {spec.section})")
    lines = [f"### {spec.name}: {spec.title} (thesis {spec.section})", "",
             f"`connrl run {spec.name} --profile {summary['profile']}` — deterministic, 1 run, "
             f"{len(rows)} lambdas, lessons of {recs[0]['params']['steps']} steps, "
             f"{wall_text(summary)}.", "",
             "| lambda | D ours (weight to 1/e) | thesis: -1/ln(lambda) | mean look-ahead (ours) |",
             "|---|---|---|---|"]
    lines += [f"| {lam:g} | {fixed(by_lam[lam]['depth'], 3)} | {fixed(-1 / math.log(lam), 3)} | "
              f"{fixed(by_lam[lam]['mean_lookahead'], 3)} |" for lam in sorted(by_lam) if lam in MARKS or lam == 0.5]
    low = [r for r in rows if r["lam"] <= 0.9]
    high = [r for r in rows if r["lam"] >= 0.9]
    lines += ["", f"Thesis (5.1.1): \"D increases gradually as lambda increases toward 0.9, and increases rapidly as "
              f"lambda increases over 0.9.\" Ours: D rises by {low[-1]['depth'] - low[0]['depth']:.2f} steps from "
              f"lambda = {low[0]['lam']:g} to {low[-1]['lam']:g} and by {high[-1]['depth'] - high[0]['depth']:.2f} "
              f"from {high[0]['lam']:g} to {high[-1]['lam']:g}; the largest deviation from -1/ln(lambda) over all "
              f"{len(rows)} lambdas is {dev:.1e} of D. **Verdict: "
              + ("reproduced** — the code's lambda-returns weight a TD(0) error k steps ahead by lambda^k, as "
                 "Eq. 5.2 does." if ok else "not reproduced** — the code's weights do not decay as lambda^k.")
              + f" The mean look-ahead (sum k w_k / sum w_k, lambda/(1-lambda) for such weights) is a looser sense "
              f"of depth: {high[-1]['depth'] - high[-1]['mean_lookahead']:.2f} steps below D at lambda = "
              f"{high[-1]['lam']:g}.",
              "", figure(draw_depth(rows, Path(out_dir) / spec.name / "figure-5-2.png"), doc, "td-depth-figure-5-2"),
              ""]
    return "\n".join(lines)
