"""docs/RESULTS.md parts for recurrent-model's action model in Ch. 7: the imperfect model of 7.5.1 (its error on
each new Task 1 lesson, from ``connrl run cup-task1``'s rows) and the fixed model of 7.5.2
(``connrl run cup-task2-frozen``)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from connrl.experiments.hidden_state import EXPERIMENTS
from connrl.report.page import figure, fixed, note, run_rows, stored
from connrl.report.plots import save_figure
from connrl.report.verdicts import claim

_SPECS = {s.name: s for s in EXPERIMENTS}
# measured on development seeds (docs/notes/cups-frozen.md); shown where the verdict is short of reproduced
FROZEN_CAUSE = ("located, not explained (development seeds, `scripts/ch7/fixed_model_probe.py`): a linear rule reads "
                "the right action from the fixed model's context at the states that need history, but the Q-net does "
                "not yet when the model is fixed, and in 3 of 5 runs still does not in the last 100 trials")
BLOCK = 10  # trials per point of the error curve
STABLE = 0.9  # "stuck to" the optimal policy: at least 90 % of the last 100 tests optimal


def _cmd(s: dict) -> str:
    return (f"`connrl run {s['experiment']} --profile {s['profile']} --runs {s['runs_per_variant']} "
            f"--seed {s['base_seed']}`")


def _errors(rows: list[dict], column: str) -> np.ndarray:
    return np.array([r[column] for r in rows if column in r])


HEADING_IMPERFECT = "The imperfect model of 7.5.1 (Task 1, recurrent-model, lambda = 0.8)"
HEADING_FROZEN = "The fixed model of 7.5.2 (Task 2, recurrent-model)"


def imperfect_model(out: Path, doc: Path) -> list[str]:
    """7.5.1: the recurrent model's errors on Task 1 (on its own lessons and on fixed random walks) beside the
    policy it supports."""
    spec = _SPECS["cup-task1"]
    summary, recs = stored(spec, Path(out))
    label = "recurrent-model lambda=0.8"
    runs = run_rows(spec, summary, Path(out), label) if summary is not None and recs else []
    runs = [r for r in runs if _errors(r, "model_wrong_steps").size]
    if not runs:
        return []
    optimal = summary["variants"][label]["quantities"]["optimal_last100"]["per_run"]
    lines = [f"### {HEADING_IMPERFECT}", "",
             f"Command: {_cmd(summary)}. Two measures of the action model, neither of which it learns from: its "
             "error on each new training lesson before it learns from it (the agent's own path), and every 50 "
             "trials its error on 200 fixed random walks (`connrl.tasks.hidden_state.model_probe`). A step is "
             "wrong when some bit of the next sensation is.", "",
             "The thesis: \"The agent never learned a perfect action model within 500 trials. For instance, if the "
             "agent had not seen a cup for 10 steps or more, the model normally was unable to predict the "
             "appearance of the cup. But this imperfect model did not prevent Q-learning from learning an optimal "
             "policy.\"", "",
             "| seed | own lessons: wrong steps, trials 1-50 | own lessons: wrong steps, last 100 trials | random "
             "walks: wrong steps after the last trial | random walks: cups appearing after >= 10 unseen steps, "
             "mispredicted | optimal in last 100 tests |", "|---|---|---|---|---|---|"]
    imperfect, unable, good = 0, 0, 0
    for seed, rows, opt in zip(summary["variants"][label]["seeds"], runs, optimal, strict=False):
        steps = _errors(rows, "model_wrong_steps")
        walk, cup, n = (_errors(rows, c) for c in ("probe_wrong_steps", "probe_cup_after_unseen_wrong",
                                                   "probe_cup_after_unseen_n"))
        imperfect += bool(walk.size) and walk[-1] > 0
        unable += bool(cup.size) and cup[-1] > 0.5
        good += opt is not None and opt >= STABLE
        lines.append(f"| {seed} | {steps[:50].mean():.3f} | {steps[-100:].mean():.3f} | "
                     f"{fixed(walk[-1] if walk.size else None, 3)} | "
                     f"{fixed(cup[-1] if cup.size else None, 2)} (of {fixed(n[-1] if n.size else None, 0)}) | "
                     f"{fixed(opt, 2)} |")
    k = len(runs)
    verdict = ("reproduced" if imperfect == unable == good == k else "partly" if imperfect and good else
               "**not reproduced**")
    claim("7.5.1: the model is never perfect, yet the policy is optimal", "7.5.1",
          "model never perfect; optimal policy found", f"model wrong on walks in {imperfect}/{k} runs, unable on "
          f"unseen cups in {unable}/{k}, policy optimal in {good}/{k}", "all three in every run",
          verdict.strip("*"), anchor=HEADING_IMPERFECT)
    lines += ["", f"**Verdict:** {verdict}. After 500 trials the model still errs on the random walks in {imperfect} "
              f"of {k} runs and mispredicts most cups that come into sight after 10 or more unseen steps in "
              f"{unable} of {k}; the greedy policy is optimal in at least {STABLE:.0%} of the last 100 tests in "
              f"{good} of {k}. On its own (by then optimal) lessons the model is nearly always right: those "
              "paths never leave a cup out of sight for long.", "",
              figure(_draw_errors(runs, Path(out) / "cup-task1" / "model-error.png"), doc, "cup-task1-model-error"),
              ""]
    return lines


def _draw_errors(runs: list[list[dict]], file: Path) -> Path:
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 3.6), dpi=120)
    for i, rows in enumerate(runs):
        e = _errors(rows, "model_wrong_steps")
        n = e.size // BLOCK
        ax.plot(BLOCK * np.arange(1, n + 1), e[:n * BLOCK].reshape(n, BLOCK).mean(axis=1), color=f"C{i}", lw=1.2,
                label=f"run {i + 1}")
        at = [r["trial"] for r in rows if "probe_wrong_steps" in r]
        bx.plot(at, _errors(rows, "probe_wrong_steps"), color=f"C{i}", lw=1.2, marker="o", ms=3)
        bx.plot(at, _errors(rows, "probe_cup_after_unseen_wrong"), color=f"C{i}", lw=1, ls="--")
    ax.set_title(f"own lessons, before learning from them ({BLOCK}-trial means)", fontsize=9)
    bx.set_title("200 fixed random walks (dashed: cups seen after >= 10 unseen steps)", fontsize=9)
    for a in (ax, bx):
        a.set_xlabel("trials")
        a.set_ylim(0, None)
        a.grid(alpha=0.3)
    ax.set_ylabel("share of steps mispredicted")
    ax.legend(fontsize=7)
    fig.suptitle("7.5.1: recurrent-model's action model on Task 1", fontsize=10)
    fig.tight_layout()
    save_figure(fig, file)
    plt.close(fig)
    return file


def fixed_verdict(stuck: int, runs: int) -> str:
    """7.5.2's "stuck to it" over the runs whose model was fixed in time: most of them stay optimal (partly: at
    least a quarter); "—" when no run was fixed in time."""
    if not runs:
        return "—"
    return "reproduced" if stuck > runs / 2 else "partly" if stuck >= runs / 4 else "**not reproduced**"


def frozen_model(out: Path, doc: Path, name: str = "cup-task2-frozen", tag=lambda summary: "") -> list[str]:
    """7.5.2: Task 2's recurrent-model with the model fixed part-way, beside the one whose model keeps learning;
    ``tag(summary)`` labels a re-check (fresh seeds) of the same claim, tallied apart."""
    summary, recs = stored(_SPECS[name], Path(out))
    if summary is None or not recs:
        return []
    mark = tag(summary)  # "" for the stored runs, " (fresh seeds ...)" for the re-check
    heading = HEADING_FROZEN + mark
    lines = [f"### {heading}", "", f"Command: {_cmd(summary)}.", "",
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
    trials = _SPECS[name].resolve(summary["profile"])[0].trials
    long = [(opt, at) for v in list(summary["variants"].values())[1:]
            for opt, at in zip(v["quantities"]["optimal_last100"]["per_run"],
                               v["quantities"]["frozen_after"]["per_run"], strict=True)
            if at is not None and at <= trials - 100]
    stuck = sum(opt is not None and opt >= STABLE for opt, _ in long)
    verdict = fixed_verdict(stuck, len(long))
    if long:
        claim(f"7.5.2: fixing the model keeps the optimal policy{mark}", "7.5.2",
              "fixed model: optimal and stuck to it",
              f"{stuck} of {len(long)} runs stay optimal (≥ {STABLE:.0%} of the last 100 tests)",
              "most runs fixed at least 100 trials before the end stay optimal, all three fixing rules pooled "
              "(partly: at least a quarter; set after the fresh runs, which the earlier rule, any run = partly, "
              "would have called partly)", verdict.strip("*"),
              "" if verdict == "reproduced" else FROZEN_CAUSE, anchor=heading, recheck=bool(mark))
    lines += ["", f"**Verdict:** {verdict} (most runs fixed in time must stay optimal; partly: at least a quarter). "
              f"Of the {len(long)} runs whose model was fixed at least 100 trials "
              f"before the end (so that the last 100 tests all come after it), {stuck} stay optimal in at least "
              f"{STABLE:.0%} of those tests. Mean share of optimal tests, last 100: "
              + ", ".join(f"{label} {m:.2f}" for label, (m, _, _) in share.items()) + ".",
              "", figure(Path(out) / name / "curve.png", doc, name), ""]
    return lines + ([] if mark else [note("cups-frozen"), ""])
