"""docs/RESULTS.md section for Ch. 4 (the survival task): ``connrl.experiments.survival``.

The orderings of 4.4.1-4.4.5 are re-derived from our runs (``THESIS_COMPARISONS``), the 4.5 speedup table is
read off the mean curves, and one evaluation play is drawn (``render_play``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from connrl.envs.survival import GRID_SIZE, render_rgb
from connrl.experiments.spec import about_the_same
from connrl.experiments.survival import EXPERIMENTS
from connrl.report.page import figure, note, stored
from connrl.report.plots import save_figure
from connrl.report.survival_accuracy import model_accuracy

_SPECS = {s.name: s for s in EXPERIMENTS}

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
_SIGN = {">": 2, ">=": 1, "~": 0, "<=": -1, "<": -2}


def relation(xs, ys) -> str:
    """Our symbol for X vs Y from per-run values: the mean difference against its standard error
    (|d| < 1 se: ~; 1-2 se: >= or <=; > 2 se: > or <)."""
    x, y = np.asarray(xs, dtype=float), np.asarray(ys, dtype=float)
    d = x.mean() - y.mean()
    se = math.sqrt((x.var(ddof=1) / x.size if x.size > 1 else 0.0) + (y.var(ddof=1) / y.size if y.size > 1 else 0.0))
    if se == 0.0:
        return "~" if d == 0 else (">" if d > 0 else "<")
    z = d / se
    return ">" if z > 2 else ">=" if z > 1 else "~" if z >= -1 else "<=" if z >= -2 else "<"


def agreement(ours: str, thesis: str) -> str:
    a, b = _SIGN[ours], _SIGN[thesis]
    if a == b:
        return "agrees"
    if a * b < 0 or abs(a - b) > 1:
        return "**disagrees**"
    return "roughly"


def _load_records(out: Path, name: str) -> tuple[dict | None, list[dict]]:
    return stored(_SPECS[name], out)


def crossing(xs, ys, level: float) -> float | None:
    """First x at which the piecewise-linear curve (xs, ys) reaches ``level`` (None if never)."""
    for i, (x, y) in enumerate(zip(xs, ys, strict=True)):
        if y >= level:
            if i == 0:
                return float(x)
            x0, y0 = xs[i - 1], ys[i - 1]
            return float(x0 + (level - y0) * (x - x0) / (y - y0))
    return None


def _mean_curve(recs: list[dict]) -> tuple[list[float], list[float]]:
    n = min(len(r["curve_x"]) for r in recs)
    return recs[0]["curve_x"][:n], list(np.mean(np.array([r["curve_y"][:n] for r in recs], dtype=float), axis=0))


def _command(summary: dict) -> str:
    n, s = summary["runs_per_variant"], summary["base_seed"]
    return (f"`connrl run {summary['experiment']} --profile {summary['profile']} --runs {n} --seed {s}` "
            f"({n} run(s) per agent, seeds {s}..{s + n - 1}, wall time {summary['timing']['wall_time_s'] / 60:.1f} "
            f"min, {sum(summary['timing']['run_wall_time_s']) / 60:.1f} min of run time)")


def _by_variant(recs: list[dict]) -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = {}
    for r in sorted(recs, key=lambda r: r["seed"]):
        out.setdefault(r["variant"], []).append(r)
    return out


def _study_section(out: Path, name: str, fig: str, doc: Path) -> tuple[list[str], dict[str, list[dict]]]:
    summary, recs = _load_records(out, name)
    if summary is None:
        return [], {}
    byv = _by_variant(recs)
    lines = [f"### {fig}: `{name}`", "", _command(summary), "",
             "| agent | final food (plays 260-300) | mean food over all tests | plays to 8 (mean curve) |",
             "|---|---|---|---|"]
    for label, rs in byv.items():
        fin = [r["metrics"]["final_food"] for r in rs]
        auc = [r["metrics"]["food_auc"] for r in rs]
        cx, cy = _mean_curve(rs)
        c8 = crossing(cx, cy, 8.0)
        lines.append(f"| {label} | {np.mean(fin):.2f} ± {np.std(fin):.2f} | {np.mean(auc):.2f} ± {np.std(auc):.2f} | "
                     f"{'not reached' if c8 is None else f'{c8:.0f}'} |")
    lines += ["", "The thesis's curves are lost (only the text survives), so there are no numbers to set beside "
              "these; the orderings of 4.4 are compared below.", "", figure(out / name / "curve.png", doc, name), ""]
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
        parts += _comparisons(studies)
    parts += _speedup(out_dir, doc)
    parts += _planning(out_dir, doc)
    parts += model_accuracy(out_dir, doc)
    parts += _tuning(out_dir) + _food(out_dir)
    parts += _evaluation(out_dir, doc)
    return "\n".join(parts) if len(parts) > 6 else ""


def _values(byv: dict, who: str, model: str | None, metric: str) -> list[float]:
    if who in ("Q", "AHC"):
        labels = [k for k in byv if k.startswith("QCON" if who == "Q" else "AHCON")]
    else:
        labels = [f"{who} ({model} model)" if who.endswith("-M") else who]
    return [r["metrics"][metric] for k in labels for r in byv.get(k, [])]


def _comparisons(studies: dict) -> list[str]:
    lines = ["### Comparisons of 4.4.1-4.4.5, re-derived from our runs", "",
             "Speed = mean food over all tests; final = mean food over the last three tests. Our symbol comes "
             "from the difference of the means against its standard error over runs (< 1 se: ~, 1-2 se: >= / <=, "
             "> 2 se: > / <). *roughly* = one step apart (e.g. > vs >=); *disagrees* = opposite or two steps "
             "apart.", "",
             "| § | repr. | model | comparison | speed: thesis | ours | | final: thesis | ours | |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    tally = {"agrees": 0, "roughly": 0, "**disagrees**": 0}
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
            ours = relation(xs, ys)
            a = agreement(ours, t)
            tally[a] += 1
            cells += [t, ours, a]
        lines.append(f"| {sec} | {rep} | {model or ''} | {x} vs {y} | " + " | ".join(cells) + " |")
    lines += ["", f"Agreement: {tally['agrees']} agree, {tally['roughly']} roughly, "
              f"{tally['**disagrees**']} disagree (of {sum(tally.values())} cells).", ""]
    return lines


_SPEEDUP_ROWS = [("QCON", "no extensions", 200), ("QCON-M (learned model)", "using a learned model", 140),
                 ("QCON-M (perfect model)", "using a perfect model", 95), ("QCON-R", "experience replay", 80),
                 ("QCON-T", "experience replay + teaching", 60)]


def _speedup(out: Path, doc: Path) -> list[str]:
    summary, recs = _load_records(out, "survival-speedup")
    source = "survival-speedup"
    if summary is None:
        summary, recs = _load_records(out, "survival-study2")
        source = "survival-study2"
    if summary is None:
        return []
    byv = _by_variant(recs)
    lines = ["### Table of 4.5: Study 2 Q-agents, plays to reach 8 food per play", "", _command(summary)
             + (" (read from Study 2's runs)" if source == "survival-study2" else ""), "",
             "| agent | thesis plays | thesis speedup | our plays (mean curve) | our speedup | per-run plays | runs |",
             "|---|---|---|---|---|---|---|"]
    base = None
    ours = {}
    for label, text, t in _SPEEDUP_ROWS:
        rs = byv.get(label, [])
        if not rs:
            continue
        c8 = crossing(*_mean_curve(rs), 8.0)
        ours[label] = c8
        if label == "QCON":
            base = c8
        per = ", ".join("—" if r["metrics"]["plays_to_8"] is None else f"{r['metrics']['plays_to_8']:.0f}" for r in rs)
        sp = f"{base / c8:.1f}" if base and c8 else "—"
        lines.append(f"| {text} | {t} | {200 / t:.1f} | {'not reached' if c8 is None else f'{c8:.0f}'} | {sp} | "
                     f"{per} | {len(rs)} |")
    order = [lab for lab, _, _ in _SPEEDUP_ROWS if lab in ours]
    reached = sorted((v, k) for k, v in ours.items() if v is not None)
    fastest = reached[0][1] if reached else None
    slowest = "QCON" if ours.get("QCON") is None or (reached and reached[-1][1] == "QCON") else reached[-1][1]
    verdict = ("agrees" if fastest == "QCON-T" and slowest == "QCON" else "**does not agree**")
    lines += ["", f"Ordering check (thesis: replay + teaching fastest, no extension slowest): fastest here is "
              f"{fastest}, slowest {slowest} — {verdict}. Rows: {', '.join(order)}. A run that never reaches 8 "
              "within 300 plays is shown as —.", ""]
    if source == "survival-speedup":
        lines += [figure(out / source / "curve.png", doc, source), ""]
    return lines


def _planning(out: Path, doc: Path) -> list[str]:
    summary, recs = _load_records(out, "survival-planning")
    if summary is None:
        return []
    lines = ["### Fig. 4.5: hypothetical actions per step (Study 2 -M agents)", "", _command(summary), "",
             "The thesis: planning drops quickly as the learning curves level off but not to zero (maximum 4).", "",
             "| agent | plays 1-20 | plays 141-160 | last 20 plays |", "|---|---|---|---|"]
    for label, rs in _by_variant(recs).items():
        h = np.mean([r["extra"]["hypothetical_per_step"] for r in rs], axis=0)
        mid = f"{np.mean(h[140:160]):.2f}" if h.size >= 160 else "—"
        lines.append(f"| {label} | {np.mean(h[:20]):.2f} | {mid} | {np.mean(h[-20:]):.2f} |")
    return lines + ["", figure(out / "survival-planning" / "curve.png", doc, "survival-planning"), ""]


def _evaluation(out: Path, doc: Path) -> list[str]:
    summary, recs = _load_records(out, "survival-eval")
    if summary is None:
        return []
    n_envs = recs[0]["params"]["eval_envs"] if recs else 0
    lines = ["### 4.3.4: QCON-T after 300 plays on random environments", "", _command(summary)
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
    lines += [f"Acceptance (≥ 12.1 food per play and ≥ 39.9% all food): {'met' if ok else '**not met**'}.", ""]
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
    summary, _ = stored(_SPECS["survival-tuning"], out)
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
    ahc = sorted((k for k in final if k.startswith("AHCON-R")), key=lambda k: -np.mean(final[k]))
    ref = ahc[1] if ahc[0] == "AHCON-R P_t=0.2" else ahc[0]  # 0.2 against the best other threshold tried
    d, two_se, same = about_the_same(final[ref], final["AHCON-R P_t=0.2"])
    pairs = [about_the_same(final[f"QCON-R P_t={a}"], final[f"QCON-R P_t={b}"])
             for a, b in (("0.1", "0.01"), ("0.01", "0.001"), ("0.1", "0.001"))]
    spread = max(abs(x[0]) for x in pairs)
    d0, two_se0, same0 = about_the_same(final["QCON-R P_t=0.01"], final["QCON-R P_t=0"])
    rel0 = d0 / np.mean(final["QCON-R P_t=0.01"])
    word = {True: "holds", False: "**does not hold**"}
    poor = "not shown" if same0 else ("holds" if d0 < 0 else "**does not hold**")
    return lines + ["", f"**Verdicts** (\"about the same\": within 2 SE of the difference, Welch, or within 10 %): "
                    f"AHCON-R P_t = 0.2 roughly the best: {word[d >= 0 or same]} (0.2 is {d:+.2f} against "
                    f"{ref.split()[-1]}, 2 SE {two_se:.2f}); QCON-R similar at 0.1, 0.01 and 0.001: "
                    f"{word[all(x[2] for x in pairs)]} (largest difference {spread:.2f}); QCON-R poor at P_t = 0: "
                    f"{poor} (0 is {d0:+.2f}, {rel0:+.0%}, against 0.01; 2 SE {two_se0:.2f}).", ""]


def _food(out: Path) -> list[str]:
    """4.2.1's food-reward claim beside ours (``survival-food``; empty when it was not run)."""
    summary, _ = stored(_SPECS["survival-food"], out)
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
    d, two_se, same = about_the_same(final[best], final["food reward 0.4"])
    return lines + ["", f"**Verdict** (within 2 SE of the difference, Welch, or within 10 %): 0.4 roughly the best: "
                    f"{'holds' if same else '**does not hold**'} (the best tried is {best.split()[-1]}; 0.4 is "
                    f"{d:+.2f} against it, 2 SE {two_se:.2f}).", ""]
