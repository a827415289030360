"""docs/RESULTS.md part for 4.4.3's model accuracy: the learned action model's prediction errors per play in
Studies 1 and 2 (``connrl run survival-study1`` / ``survival-study2``, the -M agents with the learned model).

Two measures per play, from the run's CSV rows: the on-line error (each real experience predicted before the model
learns from it; ``model_reward_abs``, ``model_enemy_bits``) and the error on fixed probe experiences, the same for
every run (``model_probe_*``, every 5 plays), which does not move with the agent's own behaviour.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from connrl.experiments.survival import EXPERIMENTS, PROBE_SEED, PROBE_SIZE
from connrl.report import verdicts
from connrl.report.page import figure, run_rows, stored
from connrl.report.plots import save_figure
from connrl.tasks.survival_models import probe_experiences

_SPECS = {s.name: s for s in EXPERIMENTS}
AGENTS = ("AHCON-M (learned model)", "QCON-M (learned model)")
MEASURES = (("model_reward_abs", "reward error (abs. r^ - r), on-line"),
            ("model_probe_reward_abs", "reward error (abs. r^ - r), fixed probes"),
            ("model_reward_sq", "reward error (squared), on-line"),
            ("model_probe_reward_sq", "reward error (squared), fixed probes"),
            ("model_enemy_bits", "wrong enemy units, on-line"),
            ("model_probe_enemy_bits", "wrong enemy units, fixed probes"))
BLOCK = 10  # plays per point of the curves
TAIL = 200  # the asymptote: the mean error over the plays after this one
BAND = 0.1  # "settled": every later block within 10 % of the asymptote (or 2 SD of the tail's blocks)
THESIS_SETTLES = 50  # 4.4.3: "approached its asymptote after approximately 50 plays"


def _counted(column: str) -> bool:
    """A fixed-probe error that the settling verdict counts: the squared reward error measures the same predictions as
    the absolute one, so it is shown but not counted again."""
    return "probe" in column and not column.endswith("_sq")


def block_curve(runs: list[list[dict]], column: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(block ends, mean over runs of each run's BLOCK-play means, each run's last-block mean) of a column of the
    training rows; rows without it (plays between probes) are skipped."""
    per_run = []
    for rows in runs:
        pts = [(r["plays"], r[column]) for r in rows if r.get("kind") == "train" and column in r]
        if not pts:
            continue
        plays, vals = np.array(pts).T
        blocks = ((plays - 1) // BLOCK).astype(int)
        per_run.append([vals[blocks == b].mean() for b in range(blocks.max() + 1)])
    if not per_run:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    n = min(len(c) for c in per_run)
    arr = np.array([c[:n] for c in per_run])
    return BLOCK * np.arange(1, n + 1), arr.mean(axis=0), arr[:, -1]


def settles(ends: np.ndarray, curve: np.ndarray) -> float | None:
    """The first block end after which the curve stays within BAND of its level over the plays after TAIL (None:
    no plays after TAIL)."""
    tail = curve[ends > TAIL]
    if tail.size == 0:
        return None
    level = tail.mean()
    # within BAND of the level, or of the tail's own scatter where that is wider (a noisy curve is level too)
    inside = np.abs(curve - level) <= max(BAND * abs(level), 2 * tail.std())
    for i in range(curve.size):
        if inside[i:].all():
            return float(ends[i])
    return None


def _study_rows(out: Path, name: str, panels: dict) -> tuple[list[str], list[tuple], str]:
    summary, recs = stored(_SPECS[name], out)
    if summary is None or not recs:
        return [], [], ""
    lines, found = [], []
    for agent in AGENTS:
        runs = run_rows(_SPECS[name], summary, out, agent)
        for column, text in MEASURES:
            ends, curve, last = block_curve(runs, column)
            if curve.size == 0:
                continue
            panels.setdefault(column, []).append((f"{name[-6:]}, {agent.split()[0]}", ends, curve))
            s = settles(ends, curve)
            found.append({"column": column, "settles": s, "last": last, "who": f"{name[-6:]} {agent.split()[0]}",
                          "kept": curve[-1] / curve[0], "final": curve[-1],
                          "rep": "global" if name.endswith("1") else "local"})
            at = {int(e): v for e, v in zip(ends, curve, strict=True)}
            lines.append(f"| {name} | {agent} | {text} | {at.get(10, float('nan')):.4f} | "
                         f"{at.get(50, float('nan')):.4f} | {curve[-1]:.4f} | {'-' if s is None else f'{s:.0f}'} | "
                         f"{last.min():.4f} |")
    n = summary["runs_per_variant"]
    return lines, found, f"`connrl run {name} --profile {summary['profile']} --runs {n} --seed {summary['base_seed']}`"


def trivial_errors(representation: str) -> tuple[float, float, float, float]:
    """For scale, on the probes: the errors of predicting r = 0 always (absolute), every enemy unit off, the enemy
    units unchanged by the move, and predicting r = 0 (squared)."""
    probes = probe_experiences(representation, PROBE_SEED, PROBE_SIZE)
    return (float(np.mean([abs(r) for _, _, r, _ in probes])),
            float(np.mean([np.mean(y[52:84] > 0) for *_, y in probes])),
            float(np.mean([np.mean((x[52:84] > 0) != (y[52:84] > 0)) for x, _, _, y in probes])),
            float(np.mean([r * r for _, _, r, _ in probes])))


def _play(p: float | None) -> str:
    return "-" if p is None else f"{p:.0f}"


def _scale_lines(probes: list[dict]) -> list[str]:
    """The probe errors of trivial predictors beside the learned model's final ones (empty without probes)."""
    if not probes:
        return []
    scale = {rep: trivial_errors(rep) for rep in ("global", "local")}
    enemy = all(f["final"] < min(scale[f["rep"]][1:3]) for f in probes if f["column"] == "model_probe_enemy_bits")
    reward = all(f["final"] < scale[f["rep"]][0] for f in probes if f["column"] == "model_probe_reward_abs")
    squared = [f for f in probes if f["column"] == "model_probe_reward_sq"]
    beat_sq = all(f["final"] < scale[f["rep"]][3] for f in squared)
    lines = ["For scale, on the same probes (Study 1 global / Study 2 local): always predicting r = 0 errs by "
             f"{scale['global'][0]:.3f} / {scale['local'][0]:.3f} (absolute) and {scale['global'][3]:.4f} / "
             f"{scale['local'][3]:.4f} (squared); predicting every enemy unit off errs by "
             f"{scale['global'][1]:.4f} / {scale['local'][1]:.4f}, and leaving them as they were by "
             f"{scale['global'][2]:.4f} / {scale['local'][2]:.4f}. After 300 plays the learned enemy nets "
             + ("beat" if enemy else "do **not** beat") + " both enemy baselines in every study and agent; the "
             "learned reinforcement nets " + ("beat" if reward else "do **not** beat") + " predicting 0 in absolute "
             "error"]
    if squared:
        lines[0] += (" and " + ("beat" if beat_sq else "do **not** beat") + " it in squared error, the error they "
                     "are trained to reduce. A net that predicts the mean reinforcement of a state, as least squares "
                     "does, errs in absolute terms on every step where a rare food or death was possible but did not "
                     "happen, so the absolute error can stay above predicting 0 even for a good model "
                     "(`python scripts/ch4/model_probe.py`; docs/RECONSTRUCTION.md, \"Survival agents\", model "
                     "nets).")
    else:
        lines[0] += " (these runs predate the squared error's record)."
    return lines + [""]


def _draw(panels: dict, file: Path) -> Path:
    fig, axes = plt.subplots(3, 2, figsize=(10, 9.0), dpi=110, sharex=True)
    for ax, (column, text) in zip(axes.flat, MEASURES, strict=True):
        for i, (label, ends, curve) in enumerate(panels.get(column, [])):
            ax.plot(ends, curve, color=f"C{i}", lw=1.4, label=label)
        ax.axvline(THESIS_SETTLES, color="k", ls="--", lw=0.7)
        ax.set_title(text, fontsize=9)
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        if panels.get(column):
            ax.legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("plays")
    fig.suptitle(f"4.4.3: learned-model prediction errors, mean over runs of {BLOCK}-play means "
                 f"(dashed: play {THESIS_SETTLES})", fontsize=10)
    fig.tight_layout()
    save_figure(fig, file)
    plt.close(fig)
    return file


def model_accuracy(out: Path, doc: Path) -> list[str]:
    """The table, figure and verdict of 4.4.3's accuracy claims (empty when neither study was run)."""
    panels: dict = {}
    rows, found, commands = [], [], []
    for name in ("survival-study1", "survival-study2"):
        lines, f, command = _study_rows(Path(out), name, panels)
        rows, found = rows + lines, found + f
        commands += [command] if command else []
    if not rows:
        return []
    probes = [f for f in found if _counted(f["column"])]
    near = [f for f in probes if f["settles"] is not None and f["settles"] <= 2 * THESIS_SETTLES]
    never_zero = all(f["last"].min() > 0 for f in found)
    kept = [f["kept"] for f in probes]  # final probe error as a share of plays 1-10's
    where = "; ".join(f"{text.split(',')[0]}: " + ", ".join(f"{f['who']} {_play(f['settles'])}" for f in probes
                                                          if f["column"] == column)
                      for column, text in MEASURES if _counted(column))
    head = ["### 4.4.3: the learned model's prediction accuracy (Studies 1 and 2)", "",
            " and ".join(commands) + ": the -M agents with the learned model, errors per play from the run records.",
            "", "The thesis: \"In both studies, the model's prediction accuracy approached its asymptote after "
            "approximately 50 plays.\" \"The agents never acquired a nearly perfect model for this nondeterministic "
            "world, even after hundreds of plays.\"", "",
            f"| experiment | agent | error | plays 1-{BLOCK} | plays 41-50 | last {BLOCK} plays | settles at play "
            f"(within {BAND:.0%} or 2 SD of plays {TAIL + 1}+) | lowest last-{BLOCK} error of a run |",
            "|---|---|---|---|---|---|---|---|"]
    level = ("no probe errors in these runs (they were made before the probes were recorded)" if not probes else
             f"on the fixed probes {len(near)} of {len(probes)} curves settle by play {2 * THESIS_SETTLES} (within "
             "twice the thesis's 50 plays) — " + ("reproduced" if len(near) == len(probes) else
                                                  "**not reproduced**" if not near else "partly")
             + f" (settling plays, {where})")
    verdict = [
        "", f"**Verdict.** Levelling off: {level}. The on-line errors also move with the agent's behaviour (it "
        "meets other states as it improves), so they are no clean measure of the model. Never nearly perfect: "
        + ("reproduced — no run's error reaches 0 after 300 plays" if never_zero
           else "**not reproduced** — some run's error reaches 0")
        + (f"; the last {BLOCK} plays' probe errors are {min(kept):.0%}-{max(kept):.0%} of those of plays "
           f"1-{BLOCK}." if kept else "."), ""]
    verdict += _scale_lines([f for f in found if "probe" in f["column"]])
    heading = "4.4.3: the learned model's prediction accuracy (Studies 1 and 2)"
    if probes:
        verdicts.claim("4.4.3: model accuracy near its asymptote after ~50 plays", "4.4.3", "about 50 plays",
                       f"{len(near)} of {len(probes)} probe-error curves settle by play {2 * THESIS_SETTLES}",
                       f"every fixed-probe curve settles (within {BAND:.0%} or 2 SD of its level after play {TAIL}) "
                       f"by play {2 * THESIS_SETTLES}; no test over runs", verdicts.REPRODUCED
                       if len(near) == len(probes) else verdicts.NOT_REPRODUCED if not near else verdicts.PARTLY,
                       anchor=heading)
    verdicts.claim("4.4.3: the learned model never nearly perfect", "4.4.3", "never nearly perfect",
                   "lowest last-10-play error of a run > 0" if never_zero else "some run's error reaches 0",
                   "no run's error reaches 0 after 300 plays", verdicts.REPRODUCED if never_zero
                   else verdicts.NOT_REPRODUCED, anchor=heading)
    return head + rows + verdict + [figure(_draw(panels, Path(out) / "survival-model-accuracy.png"), doc,
                                           "survival-model-accuracy"), ""]
