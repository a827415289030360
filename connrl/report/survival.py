"""docs/RESULTS.md section for Ch. 4 (the survival task): ``connrl.experiments.survival``.

The orderings of 4.4.1-4.4.5 are re-derived from our runs (``THESIS_COMPARISONS``), the 4.5 speedup table is
read off the mean curves, and one evaluation play is drawn (``render_play``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from connrl.envs.survival import GRID_SIZE, render_rgb
from connrl.experiments.survival import EXPERIMENTS, FRESH_SEED  # noqa: F401 (the page lists the sections' experiments)
from connrl.report import checks, verdicts
from connrl.report.page import figure, load_summary, note, recheck_tag
from connrl.report.plots import save_figure
from connrl.report.survival_accuracy import model_accuracy
from connrl.report.survival_speedup import by_variant, command, crossing, load_records, mean_curve, speedup

# 4.3.4 histogram: % of plays with 0..15 pieces of food
THESIS_HISTOGRAM = [0.1, 0.3, 0.8, 1.8, 2.2, 2.9, 4.0, 4.1, 3.8, 3.7, 3.4, 4.1, 5.4, 8.2, 15.2, 39.9]


# ---------------------------------------------------------------------------------------------- results

# 4.4.1-4.4.5: (section, representation, model or None, X, Y, thesis relation in speed, in final performance).
# "Q" and "AHC" stand for all agents of a kind (4.4.1). Symbols as in 4.4: > better, >= slightly better, ~ similar.
THESIS_COMPARISONS = [
    ("4.4.1", "global", None, "Q", "AHC", ">", ">"), ("4.4.1", "local", None, "Q", "AHC", "~", "~"),
    ("4.4.2", "global", None, "AHCON-R", "AHCON", ">", "~"), ("4.4.2", "global", None, "QCON-R", "QCON", ">", "~"),
    ("4.4.2", "local", None, "AHCON-R", "AHCON", ">", ">="), ("4.4.2", "local", None, "QCON-R", "QCON", ">", ">"),
    ("4.4.3", "global", "perfect", "AHCON-M", "AHCON", ">", ">="),
    ("4.4.3", "global", "perfect", "QCON-M", "QCON", ">", "~"),
    ("4.4.3", "global", "learned", "AHCON-M", "AHCON", "~", "~"),
    ("4.4.3", "global", "learned", "QCON-M", "QCON", "<", "<"),
    ("4.4.3", "local", "perfect", "AHCON-M", "AHCON", ">", ">"),
    ("4.4.3", "local", "perfect", "QCON-M", "QCON", ">", ">"),
    ("4.4.3", "local", "learned", "AHCON-M", "AHCON", ">", ">="),
    ("4.4.3", "local", "learned", "QCON-M", "QCON", ">", "~"),
    ("4.4.4", "global", None, "AHCON-T", "AHCON-R", "~", "~"), ("4.4.4", "global", None, "QCON-T", "QCON-R", "~", "~"),
    ("4.4.4", "local", None, "AHCON-T", "AHCON-R", ">=", "~"), ("4.4.4", "local", None, "QCON-T", "QCON-R", ">", "~"),
    ("4.4.5", "global", "perfect", "AHCON-R", "AHCON-M", ">=", "<="),
    ("4.4.5", "global", "perfect", "QCON-R", "QCON-M", ">", ">="),
    ("4.4.5", "global", "learned", "AHCON-R", "AHCON-M", ">", "~"),
    ("4.4.5", "global", "learned", "QCON-R", "QCON-M", ">", ">"),
    ("4.4.5", "local", "perfect", "AHCON-R", "AHCON-M", "<=", "<="),
    ("4.4.5", "local", "perfect", "QCON-R", "QCON-M", "~", "~"),
    ("4.4.5", "local", "learned", "AHCON-R", "AHCON-M", ">=", "~"),
    ("4.4.5", "local", "learned", "QCON-R", "QCON-M", ">", ">"),
]
PLANNING_FLOOR = 0.4  # Fig. 4.5 "did not drop close to zero": a tenth of the maximum of 4 hypothetical actions
_COMPARISONS_HEADING = "Comparisons of 4.4.1-4.4.5, re-derived from our runs"
_REPRESENTATION_HEADING = "4.4.1: final performance under the two action representations"
# measured on development seeds (docs/notes/survival-study2-gap.md); shown only where the verdict is not "reproduced"
_GAP_CAUSE = ("partly measured for QCON, QCON-R and AHCON on 3 development seeds: four action nets on the global "
              "inputs fall as far short, so the cost goes with giving up Study 1's shared rotated net, not with the "
              "local frame; plain QCON's four nets learn more slowly at Table 4.1's rate and stall at the doubled "
              "one (\"Why Study 2 falls short\")")


def _study_section(out: Path, name: str, fig: str, doc: Path,
                   lost_note: bool = True) -> tuple[list[str], dict[str, list[dict]]]:
    summary, recs = load_records(out, name)
    if summary is None:
        return [], {}
    byv = by_variant(recs)
    lines = [f"### {fig}: `{name}`", "", command(summary), "",
             "| agent | final food (plays 260-300) | mean food over all tests | plays to 8 (mean curve) |",
             "|---|---|---|---|"]
    for label, rs in byv.items():
        fin = [r["metrics"]["final_food"] for r in rs]
        auc = [r["metrics"]["food_auc"] for r in rs]
        cx, cy = mean_curve(rs)
        c8 = crossing(cx, cy, 8.0)
        lines.append(f"| {label} | {np.mean(fin):.2f} ± {np.std(fin):.2f} | {np.mean(auc):.2f} ± {np.std(auc):.2f} | "
                     f"{'not reached' if c8 is None else f'{c8:.0f}'} |")
    lost = ("The thesis's curves are lost (only the text survives), so there are no numbers to set beside these; "
            "the orderings of 4.4 are compared below.")
    lines += ["", *([lost, ""] if lost_note else []), figure(out / name / "curve.png", doc, name), ""]
    return lines, byv


def results_section(out_dir: Path, doc: Path = Path("docs/RESULTS.md")) -> str:
    out_dir = Path(out_dir)
    parts = ["## Chapter 4: the survival task", "", note("survival-intro"), ""]
    studies = {}
    for name, fig, rep in (("survival-study1", "Fig. 4.3 (Study 1, global)", "global"),
                           ("survival-study2", "Fig. 4.4 (Study 2, local)", "local")):
        lines, byv = _study_section(out_dir, name, fig, doc)
        parts += lines
        if byv:
            studies[rep] = byv
    if studies:
        parts += _comparisons(studies) + _representation(studies)
        parts += [note("survival-study2-gap"), ""] if {"global", "local"} <= set(studies) else []
    parts += speedup(out_dir, doc, cause=_GAP_CAUSE)
    parts += _fresh(out_dir, doc)
    parts += _planning(out_dir, doc)
    parts += model_accuracy(out_dir, doc)
    parts += _tuning(out_dir) + _food(out_dir)
    parts += _evaluation(out_dir, doc)
    return "\n".join(parts) if len(parts) > 6 else ""


def _fresh(out: Path, doc: Path) -> list[str]:
    """Issue 31's check: Study 1 and 2 again on seeds no development choice saw; the comparison, representation and
    4.5 verdicts re-applied, as re-checks (tallied apart). Runs on other seeds or profiles are labelled as such."""
    parts, studies, summaries = [], {}, []
    for name, fig, rep in (("survival-study1-fresh", "Study 1 (global) on fresh seeds", "global"),
                           ("survival-study2-fresh", "Study 2 (local) on fresh seeds", "local")):
        summaries += [s for s in [load_summary(out, name)] if s is not None]
        lines, byv = _study_section(out, name, fig, doc, lost_note=False)
        parts += lines
        if byv:
            studies[rep] = byv
    if not studies:
        return []
    tag = recheck_tag(summaries, FRESH_SEED, 7)
    parts += _comparisons(studies, tag) + _representation(studies, tag)
    parts += speedup(out, doc, "survival-study2-fresh", tag, factor=1.5, cause=_GAP_CAUSE)
    return [note("survival-fresh"), "", *parts]


def _values(byv: dict, who: str, model: str | None, metric: str) -> list[float]:
    if who in ("Q", "AHC"):
        labels = [k for k in byv if k.startswith("QCON" if who == "Q" else "AHCON")]
    else:
        labels = [f"{who} ({model} model)" if who.endswith("-M") else who]
    return [r["metrics"][metric] for k in labels for r in byv.get(k, [])]


def _comparisons(studies: dict, tag: str = "") -> list[str]:
    lines = [f"### {_COMPARISONS_HEADING}{tag}", "",
             "Speed = mean food over all tests; final = mean food over the last three tests; X vs Y per run "
             "(\"Q\" / \"AHC\" pool the runs of all agents of a kind, as 4.4.1 does). The rules "
             "(`connrl/report/verdicts.py`): > and < need X significantly better / worse than Y (one-sided Welch "
             f"t-test at {verdicts.ALPHA:g}); ~ needs the same within ±10 % of Y's mean (TOST at "
             f"{verdicts.ALPHA:g}: the 90 % CI of the difference inside the margin; the thesis gives no margin, "
             "10 % is the page's default); >= and <= (\"slightly\") need X not significantly on the other side "
             "and either significantly on this side or the same within 10 %. A cell is *contradicted* when the "
             "test finds the opposite (or a difference where the thesis has ~), *undetermined* when the runs "
             "decide neither.", "",
             "| § | repr. | model | comparison | speed: thesis | ours | | final: thesis | ours | |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    by_sec: dict[str, list[str]] = {}
    for sec, rep, model, x, y, t_speed, t_final in THESIS_COMPARISONS:
        byv = studies.get(rep)
        if not byv:
            continue
        cells = []
        for metric, t in (("food_auc", t_speed), ("final_food", t_final)):
            xs, ys = _values(byv, x, model, metric), _values(byv, y, model, metric)
            if not xs or not ys:
                cells += [t, "—", ""]
                continue
            word, ours = checks.relation_check(xs, ys, t)
            by_sec.setdefault(sec, []).append(word)
            cells += [t, ours, word if word == checks.AGREES else f"**{word}**"]
        lines.append(f"| {sec} | {rep} | {model or ''} | {x} vs {y} | " + " | ".join(cells) + " |")
    every = [w for ws in by_sec.values() for w in ws]
    lines += ["", f"Cells: {checks.tally(every)}.", ""]
    what = {"4.4.1": "AHC- vs Q-agents", "4.4.2": "experience replay", "4.4.3": "action models",
            "4.4.4": "teaching", "4.4.5": "experience replay vs action models"}
    for sec, words in by_sec.items():
        verdicts.claim(f"Table of {sec} ({what[sec]}){tag}", sec, "the table's > / ~ / < cells (speed, final)",
                       checks.tally(words), "each cell by the rules above (Welch one-sided for > <; TOST ±10 % "
                       "for ~); all agree = reproduced", checks.claim_verdict(words),
                       anchor=_COMPARISONS_HEADING + tag, recheck=bool(tag))
    return lines


def _gap_cause(words) -> str:
    return "" if checks.claim_verdict(words) == verdicts.REPRODUCED else _GAP_CAUSE


def _representation(studies: dict, tag: str = "") -> list[str]:
    """4.4.1's sentence on the action representations, per agent: final food, global (Study 1) against local."""
    if not {"global", "local"} <= set(studies):
        return []
    g, lo = studies["global"], studies["local"]
    lines = [f"### {_REPRESENTATION_HEADING}{tag}", "",
             "The thesis (4.4.1): \"Q-agents' final performance was basically unaffected by using different action "
             "representations, while for AHC-agents, the local action representation apparently worked better than "
             "the global action representation as far as the final performance is concerned.\" Per agent, final "
             "food of Study 1 (global) against Study 2 (local). Q-agents: \"basically unaffected\" is read as the "
             "same within ±10 % of the global runs' mean (TOST at 0.05; the thesis gives no margin). AHC-agents: "
             "local better (one-sided Welch at 0.05).", "",
             "| agent | global | local | local - global | verdict | numbers |", "|---|---|---|---|---|---|"]
    q_words, a_words, q_ours, a_ours = [], [], [], []
    for label in g:
        if label not in lo:
            continue
        xs = [r["metrics"]["final_food"] for r in g[label]]
        ys = [r["metrics"]["final_food"] for r in lo[label]]
        mg, ml = float(np.mean(xs)), float(np.mean(ys))
        if label.startswith("QCON"):
            c = checks.compare_runs(xs, ys)
            word = {verdicts.SAME: checks.AGREES, verdicts.DIFFERENT: checks.CONTRADICTED}.get(
                c.verdict if c else "", checks.OPEN)
            shown, numbers = checks.same_word(c), checks.comparison_text(c, xs, ys)
            q_words.append(word)
            q_ours.append(f"{label} {mg:.2f} → {ml:.2f}")
        else:
            v, p = checks.better_runs(xs, ys)
            word = {"yes": checks.AGREES, "no": checks.CONTRADICTED}.get(v, checks.OPEN)
            shown = {"yes": "local better", "no": "local worse"}.get(v, "not separated")
            numbers = "fewer than 2 runs a side" if p is None else f"one-sided Welch p (local better) = {p:.2g}"
            a_words.append(word)
            a_ours.append(f"{label} {mg:.2f} → {ml:.2f}")
        lines.append(f"| {label} | {mg:.2f} | {ml:.2f} | {ml - mg:+.2f} ({(ml - mg) / mg if mg else float('nan'):+.0%})"
                     f" | {shown} ({word}) | {numbers} |")
    lines += ["", f"Q-agents basically unaffected: {checks.claim_verdict(q_words)} ({checks.tally(q_words)}); "
              f"AHC-agents better with the local representation: {checks.claim_verdict(a_words)} "
              f"({checks.tally(a_words)}).", ""]
    verdicts.claim(f"4.4.1: Q-agents' final performance unaffected by the representation{tag}", "4.4.1",
                   "basically unaffected (global vs local)", "; ".join(q_ours),
                   "per Q-agent, final food global vs local the same within ±10 % of global (TOST at 0.05)",
                   checks.claim_verdict(q_words), _gap_cause(q_words), anchor=_REPRESENTATION_HEADING + tag,
                   recheck=bool(tag))
    verdicts.claim(f"4.4.1: AHC-agents' final performance better with the local representation{tag}", "4.4.1",
                   "local apparently better", "; ".join(a_ours),
                   "per AHC-agent, final food local > global (one-sided Welch at 0.05)",
                   checks.claim_verdict(a_words), _gap_cause(a_words), anchor=_REPRESENTATION_HEADING + tag,
                   recheck=bool(tag))
    return lines


def _planning(out: Path, doc: Path) -> list[str]:
    summary, recs = load_records(out, "survival-planning")
    if summary is None:
        return []
    heading = "Fig. 4.5: hypothetical actions per step (Study 2 -M agents)"
    lines = [f"### {heading}", "", command(summary), "",
             "The thesis: planning drops quickly as the learning curves level off but not to zero (maximum 4).", "",
             "| agent | plays 1-20 | plays 141-160 | last 20 plays | drops (plays 1-20 vs last 20) |",
             "|---|---|---|---|---|"]
    words, ours = [], []
    for label, rs in by_variant(recs).items():
        per = [np.asarray(r["extra"]["hypothetical_per_step"], float) for r in rs]
        h = np.mean(per, axis=0)
        mid = f"{np.mean(h[140:160]):.2f}" if h.size >= 160 else "—"
        first, last = [float(np.mean(x[:20])) for x in per], [float(np.mean(x[-20:])) for x in per]
        drop, p = checks.better_runs(first, last, higher_is_better=False)
        not_zero = min(last) >= PLANNING_FLOOR
        word = checks.AGREES if drop == "yes" and not_zero else \
            checks.CONTRADICTED if drop == "no" or not not_zero else checks.OPEN
        words.append(word)
        kind = label.split("(")[-1].split()[0]
        ours.append(f"{label.split()[0]} ({kind}) {np.mean(first):.2f} → {np.mean(last):.2f}")
        shown = {"yes": "drops", "no": "**rises**"}.get(drop, "not separated")
        shown += "" if p is None else f", {verdicts.p_text(p)}"
        lines.append(f"| {label} | {np.mean(h[:20]):.2f} | {mid} | {np.mean(h[-20:]):.2f} | {shown} |")
    lines += ["", f"Rule: per agent, the last 20 plays' mean below plays 1-20's (one-sided Welch over runs at 0.05) "
              f"and every run's last-20 mean at least {PLANNING_FLOOR:g} (a tenth of the maximum 4: \"not close to "
              f"zero\"). {checks.tally(words)}.", ""]
    verdicts.claim("Fig. 4.5: planning drops as learning levels off, not to zero", "4.4.3",
                   "drops quickly, not close to zero (max 4)", "; ".join(ours),
                   f"per -M agent: plays 1-20 > last 20 (one-sided Welch at 0.05), every run's last 20 ≥ "
                   f"{PLANNING_FLOOR:g}", checks.claim_verdict(words), anchor=heading)
    return lines + [figure(out / "survival-planning" / "curve.png", doc, "survival-planning"), ""]


def _evaluation(out: Path, doc: Path) -> list[str]:
    summary, recs = load_records(out, "survival-eval")
    if summary is None:
        return []
    n_envs = recs[0]["params"]["eval_envs"] if recs else 0
    lines = ["### 4.3.4: QCON-T after 300 plays on random environments", "", command(summary)
             + f"; each run evaluated on {n_envs} environments.", "",
             "| | food per play | all food | killed | ran out of energy |", "|---|---|---|---|---|",
             "| thesis (8000 environments) | 12.1 | 39.9% | 31.9% | 28.2% |"]
    m = {k: [r["metrics"][k] for r in recs] for k in ("eval_food", "eval_all_food_pct", "eval_killed_pct",
                                                      "eval_starved_pct")}
    lines.append(f"| ours (mean of {len(recs)} run(s)) | {np.mean(m['eval_food']):.2f} | "
                 f"{np.mean(m['eval_all_food_pct']):.1f}% | {np.mean(m['eval_killed_pct']):.1f}% | "
                 f"{np.mean(m['eval_starved_pct']):.1f}% |")
    for r in recs:
        lines.append(f"| run seed {r['seed']} | {r['metrics']['eval_food']:.2f} | "
                     f"{r['metrics']['eval_all_food_pct']:.1f}% | {r['metrics']['eval_killed_pct']:.1f}% | "
                     f"{r['metrics']['eval_starved_pct']:.1f}% |")
    hist = np.mean([r["extra"]["eval_histogram_pct"] for r in recs], axis=0)
    lines += ["", "Food per play, % of plays:", "", "| # | " + " | ".join(str(i) for i in range(16)) + " |",
              "|---|" + "---|" * 16, "| thesis | " + " | ".join(f"{v:.1f}" for v in THESIS_HISTOGRAM) + " |",
              "| ours | " + " | ".join(f"{v:.1f}" for v in hist) + " |", ""]
    ok = np.mean(m["eval_food"]) >= 12.1 and np.mean(m["eval_all_food_pct"]) >= 39.9
    lines += [f"Acceptance (the mean over runs ≥ 12.1 food per play and ≥ 39.9% all food; no test of spread): "
              f"{'met' if ok else '**not met**'}.", ""]
    verdicts.claim("4.3.4: QCON-T on 8000 random environments", "4.3.4", "12.1 food per play, 39.9% all food",
                   f"{np.mean(m['eval_food']):.2f} food, {np.mean(m['eval_all_food_pct']):.1f}% all food "
                   f"(mean of {len(recs)} run(s), {summary['profile']} profile)",
                   "the mean over runs at least the thesis's numbers, both (no test of spread)",
                   verdicts.REPRODUCED if ok else verdicts.NOT_REPRODUCED,
                   "" if summary["profile"] == "full" else f"{summary['profile']} profile, not the protocol",
                   anchor="4.3.4: QCON-T after 300 plays on random environments")
    if recs and recs[0]["extra"].get("example_play"):
        png = render_play(recs[0]["extra"]["example_play"], doc.parent / "figures" / "survival-play.png")
        lines += ["One evaluation play of the first run (`connrl.report.survival.render_play`):", "",
                  f"![a survival play](figures/{png.name})", ""]
    return lines


def render_play(frames: list[dict], path: Path, representation: str = "global", n_panels: int = 6) -> Path:
    """A PNG of a play: ``n_panels`` snapshots (rendered by the env's ``render_rgb``) with the agent's path so
    far drawn on each, captioned with step, food and energy."""
    import matplotlib.pyplot as plt

    idx = np.unique(np.linspace(0, len(frames) - 1, n_panels).round().astype(int))
    cols = min(3, len(idx))
    rows = (len(idx) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 4.6 * rows), dpi=110, squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, i in zip(axes.ravel(), idx, strict=False):
        f = frames[i]
        food = np.zeros((GRID_SIZE, GRID_SIZE), dtype=bool)
        for r, c in f["food"]:
            food[r, c] = True
        state = {"agent": tuple(f["agent"]), "enemies": np.array(f["enemies"]), "food": food, "energy": f["energy"],
                 "orientation": f["orientation"], "prev_action": -1, "collided": False,
                 "food_eaten": f["food_eaten"], "steps": f["steps"], "outcome": f["outcome"], "done": False}
        img = render_rgb(state, representation)
        ax.imshow(img)
        cell = img.shape[1] / GRID_SIZE
        path_rc = np.array([fr["agent"] for fr in frames[: i + 1]], dtype=float)
        ax.plot((path_rc[:, 1] + 0.5) * cell, (path_rc[:, 0] + 0.5) * cell, color="tab:blue", lw=1.2, alpha=0.7)
        title = f"step {f['steps']}: food {f['food_eaten']}, energy {f['energy']}"
        if f["outcome"]:
            title += f" [{f['outcome']}]"
        ax.set_title(title, fontsize=9)
    fig.suptitle("QCON-T after 300 plays, one test play (blue: the agent's path so far)", fontsize=10)
    fig.tight_layout()
    save_figure(fig, Path(path))
    plt.close(fig)
    return Path(path)


def _final_table(summary: dict, first: str, short=lambda label: label) -> tuple[dict, list[str]]:
    """(final food per run by variant, a table of its mean ± SE and the mean food over all tests)."""
    final = {label: v["quantities"]["final_food"]["per_run"] for label, v in summary["variants"].items()}
    lines = [f"| {first} | final food (mean ± SE) | food over all tests |", "|---|---|---|"]
    for label, v in summary["variants"].items():
        x = np.asarray(final[label], float)
        se = x.std(ddof=1) / math.sqrt(x.size) if x.size > 1 else float("nan")
        lines.append(f"| {short(label)} | {x.mean():.2f} ± {se:.2f} | {v['quantities']['food_auc']['mean']:.2f} |")
    return final, lines


def _tuning(out: Path) -> list[str]:
    """4.2.7's P_t claims beside ours (``survival-tuning``; empty when it was not run)."""
    summary, _ = load_records(out, "survival-tuning")
    if summary is None:
        return []
    final, table = _final_table(summary, "variant")
    lines = ["### 4.2.7: replay thresholds P_t (Study 1)", "",
             f"`connrl run survival-tuning --profile {summary['profile']}` ({summary['runs_per_variant']} runs per "
             "variant, seeds from 0). The thesis: \"For AHCON-R, P_t = 0.2 was found to give roughly the best "
             "performance ... For QCON-R, P_t = 0.1, 0.01 and 0.001 were tried and found to give similar "
             "performance. (P_t = 0 indeed gave poor performance.)\"", "", *table]
    if min(len(x) for x in final.values()) < 2:
        return lines + [""]
    heading = "4.2.7: replay thresholds P_t (Study 1)"
    ahc = sorted((k for k in final if k.startswith("AHCON-R")), key=lambda k: -np.mean(final[k]))
    ref = ahc[1] if ahc[0] == "AHCON-R P_t=0.2" else ahc[0]  # 0.2 against the best other threshold tried
    best_word, best_text = _roughly_best(final[ref], final["AHCON-R P_t=0.2"])
    qr = {t: final[f"QCON-R P_t={t}"] for t in ("0.1", "0.01", "0.001")}
    pairs = [(a, b, checks.compare_runs(qr[a], qr[b]))
             for a, b in (("0.1", "0.01"), ("0.01", "0.001"), ("0.1", "0.001"))]
    similar = [{verdicts.SAME: checks.AGREES, verdicts.DIFFERENT: checks.CONTRADICTED}.get(
        c.verdict if c else "", checks.OPEN) for *_, c in pairs]
    poor, p0 = checks.better_runs(final["QCON-R P_t=0.01"], final["QCON-R P_t=0"])
    d0 = float(np.mean(final["QCON-R P_t=0"]) - np.mean(final["QCON-R P_t=0.01"]))
    rel0 = d0 / np.mean(final["QCON-R P_t=0.01"])
    near = checks.compare_runs(final["QCON-R P_t=0.01"], final["QCON-R P_t=0"])
    # "poor": significantly worse and by more than the margin; worse but within +-10 % is only partly "poor"
    worse, same = poor == "no", bool(near and near.verdict == verdicts.SAME)
    if worse:
        poor_word = "partly" if same else checks.AGREES
    else:
        poor_word = checks.CONTRADICTED if poor == "yes" or same else checks.OPEN
    out = lines + ["", f"**Verdicts** ({checks.RULE_SAME}; the thesis gives no margin, so the page's default ±10 % "
                   "of the reference is used):", "",
                   f"- AHCON-R P_t = 0.2 roughly the best (the same as, or better than, the best other threshold, "
                   f"{ref.split()[-1]}): **{best_word}** — {best_text}.",
                   "- QCON-R similar at 0.1, 0.01 and 0.001 (every pair the same): "
                   f"**{checks.claim_verdict(similar)}** — " + "; ".join(
                       f"{b} against {a}: {checks.comparison_text(c, qr[a], qr[b])}" for a, b, c in pairs) + ".",
                   f"- QCON-R poor at P_t = 0 (worse than 0.01, one-sided Welch at 0.05, and not the same within "
                   f"±10 % by TOST): **{poor_word}** — 0 is {d0:+.2f} ({rel0:+.0%}) against 0.01"
                   + ("" if p0 is None else f", one-sided p (0 worse) = {1 - p0:.2g}")
                   + (f"; {checks.same_word(near)}" if near else "")
                   + ("; worse, but by less than the margin: \"poor\" says more" if poor_word == "partly" else ""), ""]
    verdicts.claim("4.2.7: AHCON-R P_t = 0.2 roughly the best", "4.2.7", "0.2 roughly the best of those tried",
                   f"0.2: {np.mean(final['AHCON-R P_t=0.2']):.2f}, best other ({ref.split()[-1]}) "
                   f"{np.mean(final[ref]):.2f}", "same within ±10 % (TOST) or significantly better than the best "
                   "other threshold", checks.claim_verdict([best_word]), anchor=heading)
    verdicts.claim("4.2.7: QCON-R similar at P_t = 0.1, 0.01, 0.001", "4.2.7", "similar performance",
                   ", ".join(f"{t}: {np.mean(final[f'QCON-R P_t={t}']):.2f}" for t in ("0.1", "0.01", "0.001")),
                   "every pair the same within ±10 % (TOST at 0.05)", checks.claim_verdict(similar), anchor=heading)
    verdicts.claim("4.2.7: QCON-R poor at P_t = 0", "4.2.7", "poor performance",
                   f"0: {np.mean(final['QCON-R P_t=0']):.2f} against 0.01: {np.mean(final['QCON-R P_t=0.01']):.2f} "
                   f"({rel0:+.0%})", "worse than 0.01 (one-sided Welch at 0.05) and beyond ±10 % (TOST)",
                   verdicts.PARTLY if poor_word == "partly" else checks.claim_verdict([poor_word]),
                   anchor=heading)
    return out


def _roughly_best(best_other, chosen) -> tuple[str, str]:
    """"``chosen`` gave roughly the best performance": agrees when it is the same as the best other value tried
    (TOST within 10 %) or significantly better; contradicted when it is significantly worse (Welch, two-sided)."""
    c = checks.compare_runs(best_other, chosen)
    up, p = checks.better_runs(best_other, chosen)
    if c is not None and c.verdict == verdicts.SAME or up == "yes":
        word = checks.AGREES
    elif c is not None and c.verdict == verdicts.DIFFERENT and c.diff < 0:
        word = checks.CONTRADICTED
    else:
        word = checks.OPEN
    return word, checks.comparison_text(c, best_other, chosen)


def _food(out: Path) -> list[str]:
    """4.2.1's food-reward claim beside ours (``survival-food``; empty when it was not run)."""
    summary, _ = load_records(out, "survival-food")
    if summary is None:
        return []
    final, table = _final_table(summary, "food reward", lambda label: label.split()[-1])
    lines = ["### 4.2.1: the food reward (Study 1, AHCON)", "",
             f"`connrl run survival-food --profile {summary['profile']}` ({summary['runs_per_variant']} runs per "
             "variant, seeds from 0; the reward for eating changed in training only). The thesis: \"a few different "
             "values were tried for Agent AHCON, and 0.4 gave roughly the best performance\".", "", *table]
    if min(len(x) for x in final.values()) < 2:
        return lines + [""]
    best = max(final, key=lambda k: np.mean(final[k]))
    chosen = final["food reward 0.4"]
    if best == "food reward 0.4":  # 0.4 has the highest mean: set it against the next best
        best = max((k for k in final if k != "food reward 0.4"), key=lambda k: np.mean(final[k]))
    word, text = _roughly_best(final[best], chosen)
    verdicts.claim("4.2.1: food reward 0.4 roughly the best for AHCON", "4.2.1", "0.4 roughly the best",
                   f"0.4: {np.mean(chosen):.2f}, best other ({best.split()[-1]}) {np.mean(final[best]):.2f}",
                   "same within ±10 % (TOST) or significantly better than the best other value",
                   checks.claim_verdict([word]), anchor="4.2.1: the food reward (Study 1, AHCON)")
    return lines + ["", f"**Verdict** ({checks.RULE_SAME}; the thesis gives no margin, so ±10 % of the best other "
                    f"value's mean): 0.4 roughly the best (the same as, or better than, the best other value tried, "
                    f"{best.split()[-1]}): **{word}** — {text}.", ""]
