"""Curves of `connrl train` runs: one run's ``curve.png`` (``connrl train`` draws it as it goes) and several runs
side by side, with their mean and spread by environment steps (``connrl plot FOLDER FOLDER ...``), as RL Zoo's
plotting scripts draw seeds.

A run's curve is its greedy evaluations where it has them (``--eval-every``), else its training trials' returns,
smoothed over the last ``SMOOTH`` trials (exploring trials are noisy). The runs are read at common steps (each holds
its latest value until its next), so their mean and spread are over the runs that have reached that step.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from connrl.own.callbacks import read_progress
from connrl.storage import atomic_write_bytes, read_json

SMOOTH = 10  # training trials averaged for a run without evaluations


def write_training_curve(out: Path, rows: list[dict], title: str) -> Path:
    """``out/curve.png``: each training trial's return and, where evaluated, the greedy mean (progress.csv's rows)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.5), dpi=110)
    ax.plot([r["steps"] for r in rows], [r["return"] for r in rows], lw=0.8, label="training trial")
    ev = [r for r in rows if r["eval_mean"] is not None]
    if ev:
        ax.plot([r["steps"] for r in ev], [r["eval_mean"] for r in ev], "o-", ms=3, lw=1, label="greedy evaluation")
        ax.legend(fontsize=8)
    ax.set_xlabel("environment steps")
    ax.set_ylabel("return")
    ax.set_title(title, fontsize=9)
    return _save(fig, out / "curve.png")


def plot_training(folder: Path) -> Path:
    """Redraw a trained agent's curve.png from its progress.csv (``connrl plot FOLDER``); settings.json, where it
    is whole (read by ``connrl.storage.read_json``: a regular file, size-capped), names the plot (only as text:
    --resume checks the file)."""
    rows = read_progress(folder / "progress.csv")
    title = str(folder)
    try:
        s = read_json(folder / "settings.json", "connrl train settings file")
        title = f"{str(s['env_id'])[:80]}, {str(s['agent'])[:20]}, seed {int(s['seed'])}"
    except (ValueError, KeyError, TypeError):  # no settings (an agent saved by the API): the folder names it
        pass
    return write_training_curve(folder, rows, title)


def run_curve(rows: list[dict]) -> tuple[np.ndarray, np.ndarray, str]:
    """(steps, values, what they are) of one run: its greedy evaluations, else its smoothed training returns."""
    ev = [r for r in rows if r["eval_mean"] is not None]
    if ev:
        return np.array([r["steps"] for r in ev], float), np.array([r["eval_mean"] for r in ev]), "greedy evaluation"
    returns = np.array([r["return"] for r in rows], float)
    smooth = np.array([returns[max(0, k + 1 - SMOOTH):k + 1].mean() for k in range(returns.size)])
    return np.array([r["steps"] for r in rows], float), smooth, f"training return (mean of the last {SMOOTH} trials)"


def runs_at(curves: list[tuple[np.ndarray, np.ndarray]], grid: np.ndarray) -> np.ndarray:
    """(runs, grid) values: each run's latest value at or before each grid step, NaN before its first and after
    its last step."""
    out = np.full((len(curves), grid.size), np.nan)
    for i, (xs, ys) in enumerate(curves):
        k = np.searchsorted(xs, grid, side="right") - 1
        ok = (k >= 0) & (grid <= xs[-1])
        out[i, ok] = ys[k[ok]]
    return out


def write_runs_curve(folders: list[Path], out: Path) -> Path:
    """``out``: every run's curve thin, their mean bold and the band of one standard deviation over the runs that
    reached each step."""
    import matplotlib.pyplot as plt

    curves, kinds = [], set()
    for folder in folders:
        xs, ys, kind = run_curve(read_progress(Path(folder) / "progress.csv"))
        if xs.size == 0:
            raise ValueError(f"{folder}/progress.csv holds no trial yet")
        curves.append((xs, ys))
        kinds.add(kind)
    if len(kinds) > 1:
        raise ValueError("some of these runs were evaluated (--eval-every) and some were not: their curves are not "
                         "the same quantity; plot them apart")
    grid = np.unique(np.concatenate([xs for xs, _ in curves]))
    values = runs_at(curves, grid)
    fig, ax = plt.subplots(figsize=(6.5, 3.8), dpi=110)
    for folder, (xs, ys) in zip(folders, curves, strict=True):
        ax.step(xs, ys, where="post", lw=0.6, alpha=0.45, label=Path(folder).name)
    counts = np.sum(~np.isnan(values), axis=0)
    mean = np.nanmean(values, axis=0)
    std = np.nanstd(values, axis=0)
    ax.step(grid, mean, where="post", lw=1.8, color="black", label=f"mean of {len(folders)} runs")
    ax.fill_between(grid, mean - std, mean + std, step="post", color="black", alpha=0.12, lw=0,
                    where=counts > 1, label="± one standard deviation")
    ax.set_xlabel("environment steps")
    ax.set_ylabel(kinds.pop(), fontsize=8)
    ax.legend(fontsize=7)
    return _save(fig, out)


def _save(fig, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    atomic_write_bytes(path, buf.getvalue())
    return path
