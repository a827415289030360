"""docs/RESULTS.md section for Ch. 6 (recharging): the behaviour library -- each behaviour's training and rate where
Ch. 6 uses it, and the Q-value maps of Figs. 6.3 / 6.4 with the applicability thresholds of 6.4.3, generated from the
shipped library (``connrl train-behaviours``) -- then the claims of 6.6 / 6.7 beside the stored runs of Exps 1-5
(``connrl.report.recharge_claims``), each experiment's table and curves, and Fig. 6.7's paths."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from connrl.envs.robot import Layout
from connrl.envs.robot.recharge import ROOMS
from connrl.envs.robot.render import draw_layout
from connrl.experiments import recharge, recharge_bound, recharge_flat
from connrl.report.page import figure, load_summary, note, recheck_tag, run_rows, stored, summary_table
from connrl.report.plots import save_figure
from connrl.report.recharge_claims import (
    EXP1,
    EXP3,
    HEADING,
    accounting,
    arms,
    board,
    checks,
    claims_table,
    draw_paths,
    library_steps,
)
from connrl.storage import FileError, check_number, read_json
from connrl.tasks.behaviours import APPLICABLE_ABOVE, LIBRARY_DIR, load_library, q_value_map
from connrl.tasks.recharge import chg_lessons
from connrl.tasks.robot import TAUGHT_COUNTS, taught_lessons

# the experiments this section covers: Exps 1-5, and the bound of what the behaviours can do
EXPERIMENTS = [*recharge_flat.EXPERIMENTS, *recharge.EXPERIMENTS, *recharge_bound.EXPERIMENTS]
FRESH = "recharge-behaviours-fresh"
THESIS = {
    "recharge-flat": "Thesis (6.6.1, Fig. 6.5): after 300 trials generally unable to recharge from rooms B and C, "
                     "colliding on more than 5 % of steps; no systematic way learned whatever the reward function.",
    "recharge-behaviours": "Thesis (6.6.2-6.6.3): Exp. 3 connects from most places in rooms A and C within 20 trials "
                           "and nearly optimally from everywhere within 60; Exp. 2 is poor after 150 trials, though "
                           "from room A it succeeds within about 10.",
    "recharge-long-delay": "Thesis (6.6.4): without grouping (lambda 0.8-0.97 tried) unable to recharge from room B; "
                           "with grouping comparable to Exp. 3; about 11 states per group.",
    "recharge-together": "Thesis (6.6.5): little progress in the first 50 trials, then rapid; slightly below Exp. 3, "
                         "and docking from any room at the end.",
    "recharge-own-library": "Thesis (6.7, 8.5): Exp. 3's robot spent about 40,000 primitive steps in all, its "
                            "behaviours' training included; 8.5 puts the behaviours' share at 2,000 (DK) + 2,000 (DP) "
                            "+ 1,500 (WFL) + 1,500 (WFR). Here each run trains its own behaviours within those steps "
                            "(ours: the thesis gives no other number for them), then learns as Exp. 3.",
    FRESH: "Exp. 3 unchanged on seeds never used in development (docs/notes/prereg-fresh-checks.md).",
}

WHERE_USED = {"DK": "docks from within 24 in of subgoal 2", "DP": "passes the door from subgoals 3-6",
              "WFL": "steps earning 8-10 (clearance kept, moving forward)", "WFR": "steps earning 8-10"}


def draw_q_map(task: str, xs, ys, grid, layout: Layout, file: Path) -> Path:
    """Figs. 6.3 / 6.4: the largest Q over actions and 4 headings on the room map, the applicability contour."""
    fig, ax = plt.subplots(figsize=(5.2, 6), dpi=110)
    draw_layout(ax, layout, labels=True)  # rooms first: the map is drawn over them, the walls drawn again on top
    im = ax.imshow(grid, origin="lower", extent=(0, layout.size[0], 0, layout.size[1]), cmap="viridis",
                   vmin=-100, vmax=100, alpha=0.9, zorder=2)
    ax.contour(xs, ys, np.nan_to_num(grid, nan=-100.0), levels=[APPLICABLE_ABOVE[task]], colors="r", linewidths=1.2,
               zorder=3)
    for w in layout.walls:
        ax.plot([w[0], w[2]], [w[1], w[3]], color="black", lw=3, zorder=4)
    fig.colorbar(im, ax=ax, shrink=0.7, label="max Q over actions and 4 headings")
    ax.set_title(f"{task}: applicable where Q > {APPLICABLE_ABOVE[task]:g} (red line)", fontsize=9)
    fig.tight_layout()
    save_figure(fig, file)
    plt.close(fig)
    return file


def draw_room_curves(spec, summary: dict, out_dir: Path, file: Path) -> Path | None:
    """Per start room, the mean over runs of the share of test tasks docked, one panel per variant (Fig. 6.6 split
    by room), from the runs' CSV rows."""
    fig, axes = plt.subplots(1, len(spec.variants), figsize=(4.5 * len(spec.variants), 3.4), dpi=110, sharey=True,
                             squeeze=False)
    drawn = False
    for ax, v in zip(axes[0], spec.variants, strict=True):
        rows = run_rows(spec, summary, out_dir, v.label)
        rows = [r for r in rows if len(r) == len(rows[0])]
        if not rows:
            continue
        xs = [r["trials"] for r in rows[0]]
        for i, room in enumerate(ROOMS):
            ax.plot(xs, np.mean([[r[f"docked_{room}"] for r in run] for run in rows], axis=0), color=f"C{i}",
                    label=f"from room {room}")
        ax.set_title(f"{v.label} ({len(rows)} runs)", fontsize=9)
        ax.set_xlabel("trials")
        ax.grid(alpha=0.3)
        drawn = True
    axes[0][0].set_ylabel("share of test tasks docked")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    if drawn:
        save_figure(fig, file)
    plt.close(fig)
    return file if drawn else None


def bound_table(spec, summary: dict) -> list[str]:
    """recharge-bound's rules beside the scripted teacher, per start room: share docked and steps of the dockings."""
    def cell(qs, name, fmt):
        v = qs.get(name, {}).get("mean")
        return "—" if v is None else format(v, fmt)

    lines = [f"### {spec.name}: {spec.title} (ours)", "",
             f"`connrl run {spec.name} --profile {summary['profile']} --seed {summary['base_seed']}` "
             f"({summary['runs_per_variant']} runs, the test tasks of the learning runs of the same seeds; "
             "docs/RECONSTRUCTION.md, \"Ch. 6 bound\"). What the shipped behaviours achieve when the choice among "
             "them is right: the yardstick for the learners above.", "",
             "| rule | docked from A / B / C | steps to dock from A / B / C | share of the teacher's reinforcement "
             "per step |", "|---|---|---|---|"]
    teacher = None
    for label, v in summary["variants"].items():
        qs = v["quantities"]
        docked = " / ".join(cell(qs, f"docked_{r}", ".2f") for r in ROOMS)
        steps = " / ".join(cell(qs, f"steps_{r}", ".0f") for r in ROOMS)
        lines.append(f"| {label} | {docked} | {steps} | {cell(qs, 'share_of_teacher', '.0%')} |")
        teacher = qs
    if teacher is not None:
        lines.append(f"| scripted teacher | {' / '.join(cell(teacher, f'teacher_docked_{r}', '.2f') for r in ROOMS)} "
                     f"| {' / '.join(cell(teacher, f'teacher_steps_{r}', '.0f') for r in ROOMS)} | 100% |")
    return [*lines, ""]


def read_library_index(path: Path) -> dict:
    """library.json (written by ``connrl train-behaviours``) checked field by field; a damaged index raises
    FileError (one line naming the file and the field) rather than a traceback in the middle of the page."""
    doc = read_json(path, "behaviour library index")
    index = doc.get("behaviours") if isinstance(doc, dict) else None
    if not isinstance(index, dict) or set(index) - set(WHERE_USED):
        raise FileError(path, "must be an object whose 'behaviours' maps behaviour names "
                        f"({', '.join(sorted(WHERE_USED))}) to their records", "behaviours")
    for name, m in index.items():
        if not isinstance(m, dict):
            raise FileError(path, "must be an object", f"behaviours.{name}")
        for key, low, high, integer in (("trials", 0, 10**7, True), ("lessons", 0, 10**7, True),
                                        ("far_share", 0, 1, False), ("final_test_performance", -1e6, 1e6, False),
                                        ("serve_rate", 0, 1, False)):
            check_number(path, f"behaviours.{name}.{key}", m.get(key), low, high, integer=integer)
    return index


def library_table(index: dict) -> list[str]:
    lines = ["## Chapter 6: hierarchical learning (Exps 1-5, Figs. 6.3-6.7)", "",
             "The behaviours the high level coordinates are Ch. 5's QCON-T skills, trained by `connrl "
             "train-behaviours` and shipped in `connrl/data/behaviours/` (one seed each; docs/RECONSTRUCTION.md, "
             "\"Behaviour library\").", "",
             "| behaviour | trials | taught lessons | far-from-goal starts | final test (reinforcement/step, 50 "
             "tasks) | where Ch. 6 uses it | rate |", "|---|---|---|---|---|---|---|"]
    for t, m in index.items():
        lines.append(f"| {t} | {m['trials']} | {m['lessons']} | {m['far_share']:.0%} | "
                     f"{m['final_test_performance']:.2f} | {WHERE_USED[t]} | {m['serve_rate']:.2f} |")
    return [*lines, ""]


def fresh_lines(data: dict) -> list[str]:
    """Exp. 3's claims re-applied to ``recharge-behaviours-fresh`` (seeds never used in development; the rules fixed
    in docs/notes/prereg-fresh-checks.md), put on the scoreboard as re-checks."""
    if FRESH not in data:
        return []
    spec, summary, out = data[FRESH]
    tag = recheck_tag([summary], recharge.FRESH_SEED, 7)
    found = checks(*arms({"recharge-behaviours": data[FRESH]}))
    board(found, tag=tag)
    return [f"### {HEADING}{tag}", "", f"Exp. 3's claims again on `{FRESH}` (the same protocol and rules; Exp. 3's "
            "high-level learner choices were picked on development seeds 100-119 by the 60-trial claim, so these "
            "runs are its test):", "", *claims_table(found), ""]


def results_section(out_dir, doc=Path("docs/RESULTS.md")) -> str:
    out_dir, doc = Path(out_dir), Path(doc)
    index_file = LIBRARY_DIR / "library.json"
    if not index_file.exists():
        return ""
    index = read_library_index(index_file)
    lines = library_table(index)
    layout, lib = Layout.load("default"), load_library()
    for task in ("DP", "DK"):
        xs, ys, grid = q_value_map(lib[task], layout)
        png = draw_q_map(task, xs, ys, grid, layout, out_dir / "behaviours" / f"{task.lower()}-q-map.png")
        share = float(np.mean(grid[~np.isnan(grid)] > APPLICABLE_ABOVE[task]))
        lines += [f"Fig. {'6.3' if task == 'DP' else '6.4'} from our {task} behaviour (noise-free scans every 12 in): "
                  f"applicable on {share:.0%} of the places the robot fits.", "",
                  figure(png, doc, f"behaviour-{task.lower()}-q-map"), ""]
    data = {}
    for spec in EXPERIMENTS:
        summary = load_summary(out_dir, spec.name)
        if summary is not None:
            data[spec.name] = (spec, summary, out_dir)
    if data:
        taught = {"CHG": sum(len(x) for x in chg_lessons(10)),
                  **{t: sum(len(x) for x in taught_lessons(t, n)) for t, n in TAUGHT_COUNTS.items()}}
        found = checks(*arms(data), library_steps(index))
        board(found)
        lines += [f"### {HEADING}", "", *claims_table(found), "",
                  "Steps spent (6.7; means over the stored runs):", "", *accounting(data, taught, index), ""]
        lines += fresh_lines(data)
    for spec in EXPERIMENTS:
        if spec.name not in data:
            continue
        summary = data[spec.name][1]
        if spec.name == "recharge-bound":
            lines += bound_table(spec, summary)
            continue
        lines += [f"### {spec.name}: {spec.title} (thesis {spec.section})", "", summary_table(summary), "",
                  THESIS[spec.name], "", figure(out_dir / spec.name / "curve.png", doc, spec.name), ""]
        rooms = draw_room_curves(spec, summary, out_dir, out_dir / spec.name / "rooms.png")
        if rooms is not None:
            lines += ["By start room (mean over runs):", "", figure(rooms, doc, f"{spec.name}-rooms"), ""]
        label = {"recharge-behaviours": EXP3, "recharge-flat": EXP1}.get(spec.name)
        _, records = stored(spec, out_dir)
        rec = next((r for r in sorted(records, key=lambda r: r["seed"]) if r["variant"] == label
                    and r.get("extra", {}).get("paths")), None)
        if rec is not None:
            png = draw_paths(rec, out_dir / spec.name / "paths.png", f"{label}: greedy paths after "
                             f"{rec['params']['trials']} trials (seed {rec['seed']})")
            lines += [f"Greedy paths of the first run after its last trial, one from each room (Fig. 6.7"
                      f"{'' if spec.name == 'recharge-behaviours' else ', for the flat learner'}):", "",
                      figure(png, doc, f"{spec.name}-paths"), ""]
    if data:
        lines += [note("recharge-status"), ""]
    return "\n".join(lines)
