"""Ch. 8's hidden state made visible: what the memoryless and the recurrent learner do at the two doorways of room C,
and whether a linear probe tells the doorways apart from what each of them sees.

The samples are the ``integration`` runs' probe records (``connrl.experiments.integration.final_tests``): every step
of the final greedy tests taken in room C within 30 in of subgoal 4 (door A) or 5 (door B), with the 14 inputs, the
Q-values, the behaviour chosen and, for the recurrent learner, the context units the choice read.

The probe (``probe_accuracy``) is a least-squares linear classifier of the doorway (A = +1, B = -1), fitted within one
run (each run's context units mean their own things) and scored on held-out trials (the steps of one trial are alike,
so a trial is never split between fit and score); its accuracy is averaged over runs.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from connrl.envs.robot.recharge import BEHAVIOUR_TASKS
from connrl.report.plots import save_figure

DP = BEHAVIOUR_TASKS.index("DP")
FOLDS = 5


def _features(samples: list[dict], view: str) -> np.ndarray:
    x = np.array([s["x"] for s in samples], dtype=float)
    if view == "inputs":
        return x
    c = np.array([s["context"] for s in samples], dtype=float)
    return c if view == "context" else np.hstack([x, c])


def probe_accuracy(samples: list[dict], view: str, ridge: float = 1e-3) -> float | None:
    """Held-out accuracy of a linear classifier of the doorway from ``view`` ("inputs", "context" or "both") over
    one run's samples, folds by trial (a fold whose fitting part holds one doorway only is skipped); None when fewer
    than 2 trials or no fold could be scored."""
    trials = np.array([s["trial"] for s in samples])
    ids = np.unique(trials)
    if len(ids) < 2:
        return None
    x, y = _features(samples, view), np.array([1.0 if s["door"] == "A" else -1.0 for s in samples])
    x = np.hstack([x, np.ones((len(x), 1))])
    right = total = 0
    for k in range(min(FOLDS, len(ids))):
        test = np.isin(trials, ids[k::FOLDS])
        if len(np.unique(y[~test])) < 2:
            continue
        a, b = x[~test], y[~test]
        w = np.linalg.solve(a.T @ a + ridge * np.eye(a.shape[1]), a.T @ b)
        right += int(np.sum(np.sign(x[test] @ w) == y[test]))
        total += int(test.sum())
    return right / total if total else None


def dp_share(samples: list[dict], door: str, start_room: str | None = None) -> float | None:
    """Share of the near-``door`` steps (from ``start_room``'s trials, or all) on which DP was chosen."""
    picks = [s["behaviour"] == DP for s in samples if s["door"] == door
             and (start_room is None or s["start_room"] == start_room)]
    return float(np.mean(picks)) if picks else None


def mean_or_none(values) -> float | None:
    vals = [v for v in values if v is not None]
    return float(np.mean(vals)) if vals else None


def probe_table(by_label: dict[str, list[list[dict]]]) -> list[str]:
    """Per learner: DP chosen at each doorway, and the probe's accuracy from what it sees."""
    lines = ["| learner | near-door steps (runs) | DP chosen at door A | at door B | at door B, trials from room B | "
             "probe: inputs | probe: context | probe: inputs + context |", "|---|---|---|---|---|---|---|---|"]
    for label, runs in by_label.items():
        runs = [r for r in runs if r]
        if not runs:
            continue
        has_context = len(runs[0][0].get("context", ())) > 0  # a recurrent net without context units has none

        def f(v):
            return "—" if v is None else f"{v:.2f}"

        cells = [f(mean_or_none(dp_share(r, "A") for r in runs)), f(mean_or_none(dp_share(r, "B") for r in runs)),
                 f(mean_or_none(dp_share(r, "B", "B") for r in runs))]
        probes = [f(mean_or_none(probe_accuracy(r, v) for r in runs)) if v == "inputs" or has_context else "—"
                  for v in ("inputs", "context", "both")]
        lines.append(f"| {label} | {sum(map(len, runs))} ({len(runs)}) | " + " | ".join(cells + probes) + " |")
    return lines


def draw_probe(by_label: dict[str, list[list[dict]]], recurrent: str, file: Path) -> Path | None:
    """Left: mean Q of each behaviour at door A and door B, per learner. Right: one recurrent run's context units
    at the two doorways, on their first two principal components."""
    labels = [k for k, runs in by_label.items() if any(runs)]
    if not labels:
        return None
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), dpi=110)
    ax = axes[0]
    width = 0.8 / (2 * len(labels))
    for i, label in enumerate(labels):
        samples = [s for run in by_label[label] for s in run]
        for j, door in enumerate("AB"):
            q = [s["q"] for s in samples if s["door"] == door]
            if not q:
                continue
            pos = np.arange(len(BEHAVIOUR_TASKS)) + (2 * i + j - len(labels) + 0.5) * width
            ax.bar(pos, np.mean(q, axis=0), width, color=f"C{i}", alpha=1.0 if door == "A" else 0.45,
                   label=f"{label}, door {door}")
    ax.set_xticks(range(len(BEHAVIOUR_TASKS)), BEHAVIOUR_TASKS)
    ax.set_ylabel("mean Q (greedy tests, near the doorway)")
    ax.set_title("Q-values in room C at subgoal 4 (door A, dark) and 5 (door B, light)", fontsize=9)
    ax.legend(fontsize=6)
    ax.grid(alpha=0.3, axis="y")
    ax = axes[1]
    run = next((r for r in by_label.get(recurrent, []) if r and len({s["door"] for s in r}) == 2), None)
    if run is not None:
        c = np.array([s["context"] for s in run])
        c0 = c - c.mean(axis=0)
        _, _, vt = np.linalg.svd(c0, full_matrices=False)
        pc = c0 @ vt[:2].T
        for door, colour in (("A", "C0"), ("B", "C3")):
            m = np.array([s["door"] == door for s in run])
            ax.scatter(pc[m, 0], pc[m, 1], s=10, color=colour, label=f"door {door}")
        ax.set_xlabel("context PC 1")
        ax.set_ylabel("context PC 2")
        ax.legend(fontsize=8)
        ax.set_title(f"{recurrent}: the 8 context units near the two doorways (one run)", fontsize=9)
    else:
        ax.axis("off")
    fig.tight_layout()
    save_figure(fig, file)
    plt.close(fig)
    return file
