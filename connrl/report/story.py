"""The whole robot story in one picture (README): Ch. 5's behaviours, Ch. 6's hierarchy over them, Ch. 8's recurrent
policy without X-Y. Panel 1 runs the shipped behaviours greedily from fixed starts (deterministic); panels 2 and 3 are
greedy paths from room B stored by the ``integration`` runs (``_b_path``: a docked one where there is one)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from connrl.core.rollout import run_trial
from connrl.envs.robot import Layout, RobotTaskEnv
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS
from connrl.envs.robot.render import draw_layout
from connrl.report.plots import save_figure
from connrl.report.recharge_claims import COLOURS
from connrl.tasks.behaviours import load_library

# (task, start pose x, y, heading deg, seed): one short greedy run of each behaviour on its own task (Ch. 5)
BEHAVIOUR_RUNS = (("WFL", 300.0, 150.0, 90.0, 1), ("DP", 246.0, 250.0, 80.0, 2), ("DK", 70.0, 80.0, 200.0, 3))


def _segments(ax, poses, behaviours) -> None:
    poses = np.asarray(poses)
    for k, b in enumerate(behaviours):
        ax.plot(poses[k:k + 2, 0], poses[k:k + 2, 1], color=COLOURS.get(b, "0.3"), lw=1.8, zorder=5)
    ax.plot(*poses[0, :2], "o", color="k", ms=4, zorder=6)


def _b_path(records, label):
    """The first run's greedy path from room B after its last trial if it docked, else the first docking from room B
    among the runs' final tests, else that first path."""
    runs = [r.get("extra", {}) for r in sorted(records, key=lambda r: r["seed"]) if r["variant"] == label]
    paths = [p for extra in runs for p in extra.get("paths", []) if p["room"] == "B"]
    docked = [p for p in paths if p["success"]] + [extra["b_solution"] for extra in runs if "b_solution" in extra]
    return docked[0] if docked else (paths[0] if paths else None)


def draw_story(records: list[dict], ch6_label: str, ch8_label: str, file: Path) -> Path | None:
    layout, lib = Layout.load("default"), load_library()
    fig, axes = plt.subplots(1, 3, figsize=(13, 5.6), dpi=110)
    ax = axes[0]
    draw_layout(ax, layout, labels=True)
    for task, x, y, heading, seed in BEHAVIOUR_RUNS:
        env = RobotTaskEnv(task)
        run_trial(env, lib[task], trial=0, learning=False, seed=seed, options={"start": (x, y, heading)})
        _segments(ax, [p[:2] for p in env.trace], [task] * (len(env.trace) - 1))
    ax.set_title("1. Behaviours (Ch. 5): DK, DP, WFL/WFR learned alone", fontsize=9)
    for ax, label, title in ((axes[1], ch6_label, "2. Hierarchy (Ch. 6): Q(state, behaviour), with X-Y"),
                             (axes[2], ch8_label, "3. Integration (Ch. 8): recurrent-Q, no X-Y")):
        draw_layout(ax, layout, labels=True)
        if ax is axes[1]:
            for name, (gx, gy) in layout.subgoals.items():
                ax.plot(gx, gy, "x", color="k", ms=6, zorder=6)
                ax.annotate(name, (gx, gy), fontsize=8, xytext=(3, 3), textcoords="offset points")
        path = _b_path(records, label)
        if path is not None:
            _segments(ax, path["poses"], path["behaviours"])
            share = np.mean([r["metrics"].get("default_docked_B") or 0.0 for r in records if r["variant"] == label])
            done = "docked" if path["success"] else "not docked"
            title += f"\nfrom room B: {done}, {len(path['behaviours'])} steps ({share:.0%} of its room-B tests dock)"
        ax.set_title(title, fontsize=9)
    for b in BEHAVIOUR_TASKS:
        axes[2].plot([], [], color=COLOURS[b], label=b)
    axes[2].legend(fontsize=7, loc="upper right")
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.tight_layout()
    save_figure(fig, file)
    plt.close(fig)
    return file
