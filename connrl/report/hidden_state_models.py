"""docs/RESULTS.md parts for recurrent-model's action model in Ch. 7: the imperfect model of 7.5.1 (its error on
each new Task 1 lesson, from ``connrl run cup-task1``'s rows) and the fixed model of 7.5.2
(``connrl run cup-task2-frozen``)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from connrl.experiments.hidden_state import EXPERIMENTS
from connrl.report.page import figure, fixed, run_rows, stored
from connrl.report.plots import save_figure

_SPECS = {s.name: s for s in EXPERIMENTS}
BLOCK = 10  # trials per point of the error curve
STABLE = 0.9  # "stuck to" the optimal policy: at least 90 % of the last 100 tests optimal


def _cmd(s: dict) -> str:
    return (f"`connrl run {s['experiment']} --profile {s['profile']} --runs {s['runs_per_variant']} "
            f"--seed {s['base_seed']}`")


def _errors(rows: list[dict], column: str) -> np.ndarray:
    return np.array([r[column] for r in rows if column in r])


def imperfect_model(out: Path, doc: Path) -> list[str]:
    """7.5.1: the recurrent model's error on each new Task 1 lesson (before learning from it) beside the policy."""
    spec = _SPECS["cup-task1"]
    summary, recs = stored(spec, Path(out))
    label = "recurrent-model lambda=0.8"
    runs = run_rows(spec, summary, Path(out), label) if summary is not None and recs else []
    runs = [r for r in runs if _errors(r, "model_wrong_steps").size]
    if not runs:
        return []
    optimal = summary["variants"][label]["quantities"]["optimal_last100"]["per_run"]
    lines = ["### The imperfect model of 7.5.1 (Task 1, recurrent-model, lambda = 0.8)", "",
             f"Command: {_cmd(summary)}; the model's error on each new training lesson before it learns from it "
             "(`model_wrong_steps`: share of steps whose next sensation it gets wrong in some bit).", "",
             "The thesis: \"The agent never learned a perfect action model within 500 trials. [...] But this "
             "imperfect model did not prevent Q-learning from learning an optimal policy.\"", "",
             "| seed | wrong steps, trials 1-50 | wrong steps, last 100 trials | wrong bits, last 100 | "
             "lessons predicted perfectly, last 100 | optimal in last 100 tests |", "|---|---|---|---|---|---|"]
    imperfect, good = 0, 0
    for seed, rows, opt in zip(summary["variants"][label]["seeds"], runs, optimal, strict=False):
        steps, bits = _errors(rows, "model_wrong_steps"), _errors(rows, "model_wrong_bits")
        imperfect += steps[-100:].mean() > 0
        good += opt is not None and opt >= STABLE
        lines.append(f"| {seed} | {steps[:50].mean():.3f} | {steps[-100:].mean():.3f} | {bits[-100:].mean():.4f} | "
                     f"{int((steps[-100:] == 0).sum())} | {fixed(opt, 2)} |")
    n = len(runs)
    verdict = ("reproduced" if imperfect == n and good == n else "partly" if imperfect and good else
               "**not reproduced**")
    lines += ["", f"**Verdict:** {verdict}. The model is still imperfect over the last 100 trials in {imperfect} of "
              f"{n} runs, and the greedy policy is optimal in at least {STABLE:.0%} of the last 100 tests in {good} "
              f"of {n}.", "", figure(_draw_errors(runs, Path(out) / "cup-task1" / "model-error.png"), doc,
                                   "cup-task1-model-error"), ""]
    return lines


def _draw_errors(runs: list[list[dict]], file: Path) -> Path:
    fig, ax = plt.subplots(figsize=(7, 3.6), dpi=120)
    for i, rows in enumerate(runs):
        e = _errors(rows, "model_wrong_steps")
        n = e.size // BLOCK
        ax.plot(BLOCK * np.arange(1, n + 1), e[:n * BLOCK].reshape(n, BLOCK).mean(axis=1), color=f"C{i}", lw=1.2,
                label=f"run {i + 1}")
    ax.set_xlabel("trials")
    ax.set_ylabel(f"share of steps mispredicted ({BLOCK}-trial means)")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title("7.5.1: recurrent-model's action model on each new Task 1 lesson", fontsize=9)
    fig.tight_layout()
    save_figure(fig, file)
    plt.close(fig)
    return file


def frozen_model(out: Path, doc: Path) -> list[str]:
    """7.5.2: Task 2's recurrent-model with the model fixed part-way, beside the one whose model keeps learning."""
    summary, recs = stored(_SPECS["cup-task2-frozen"], Path(out))
    if summary is None or not recs:
        return []
    lines = ["### The fixed model of 7.5.2 (Task 2, recurrent-model)", "", f"Command: {_cmd(summary)}.", "",
             "The thesis: without a fix the agent \"could not stabilize on the optimal policy; it oscillated\"; "
             "\"I fixed the model at some point of learning and allowed only changes to the Q-net. In such a "
             "setup, the agent found the optimal policy and indeed stuck to it.\"", "",
             "| variant | model fixed after trials (per run) | optimal in last 100 tests (per run) | mean | "
             f"mean steps, last 100 | runs at ≥ {STABLE:.0%} optimal |", "|---|---|---|---|---|---|"]
    share = {}
    for label, v in summary["variants"].items():
        q = v["quantities"]
        per = [x for x in q["optimal_last100"]["per_run"] if x is not None]
        share[label] = (np.mean(per) if per else 0.0, sum(x >= STABLE for x in per), len(per))
        when = ", ".join("never" if x is None else fixed(x, 0) for x in q["frozen_after"]["per_run"])
        lines.append(f"| {label} | {when} | {', '.join(fixed(x, 2) for x in per)} | {fixed(share[label][0], 2)} | "
                     f"{fixed(q['mean_steps_last100']['mean'], 2)} | {share[label][1]}/{share[label][2]} |")
    free = next(iter(share.values()))
    fixed_runs = list(share.values())[1:]
    stuck = all(s[1] == s[2] for s in fixed_runs)
    better = all(s[0] > free[0] for s in fixed_runs)
    verdict = "reproduced" if stuck and better else "partly" if better else "**not reproduced**"
    lines += ["", f"**Verdict:** {verdict}. Fixing the model " + ("raises" if better else "does not raise") +
              f" the share of optimal tests over the last 100 (learning throughout: {free[0]:.2f}); "
              + ("every run with a fixed model stays optimal." if stuck else
                 "not every run with a fixed model stays optimal."),
              "", figure(Path(out) / "cup-task2-frozen" / "curve.png", doc, "cup-task2-frozen"), ""]
    return lines
