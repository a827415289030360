"""Chapter 4: the eight frameworks on the survival task (Figs. 4.3-4.5, the tables of 4.3.4, 4.4 and 4.5).

Protocol (4.3.1): each run draws 300 training and 50 test environments (food layouts) from its seed; the
agent plays the 300 training environments in order, learning; before the first play and after every 20
it plays the 50 test environments with learning off and T = 0; the curve is the mean food per test play.
A thesis study is 7 runs per agent.

Experiments (``connrl run NAME``):

* ``survival-study1`` — Fig. 4.3: all agents, global action representation, Table 4.1 parameters;
* ``survival-study2`` — Fig. 4.4: all agents, local representation, learning rates doubled (4.3.3);
* ``survival-planning`` — Fig. 4.5: hypothetical actions per step of the -M agents of Study 2;
* ``survival-speedup`` — the table of 4.5: plays until the Study 2 Q-agents reach 8 food per play;
* ``survival-eval`` — 4.3.4: QCON-T (global) after 300 plays, tested on 8000 random environments.

The -M agents come with both models of 4.2.5 ("learned" and "perfect"), as 4.4.3 compares both.

Per-run quantities: ``final_food`` (mean food per test play over the last three tests, plays 260-300, our
measure of "final performance"), ``food_auc`` (mean over all 16 tests, our measure of "learning speed"),
``plays_to_8`` (first test at which the run reaches 8 food per play). The speedup table of 4.5 is read off
the *mean* curve of the runs, as the thesis's learning curves are means over its 7 experiments.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from connrl.envs.survival import SurvivalEnv, environment_sets
from connrl.experiments.protocol import run_trial
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant
from connrl.tasks.survival import SurvivalAgentParams, make_survival_agent

SURVIVAL_PARAMS = {
    "framework": "QCON",  # one of connrl.agents.survival.FRAMEWORKS
    "model": "learned",  # action model of the -M agents (4.2.5)
    "representation": "global",  # 4.2.3
    "lr_scale": 1.0,  # Study 2: 2.0 (4.3.3)
    "train_plays": 300,  # 4.3.1
    "test_envs": 50,  # 4.3.1
    "test_every": 20,  # 4.3.1
    "eval_envs": 0,  # 4.3.4: 8000 after training (survival-eval only)
    "curve": "food",  # "food" (Figs. 4.3/4.4) or "planning" (Fig. 4.5: hypothetical actions per step)
    "planning_block": 10,  # plays averaged per point of the planning curve
}


def _agent_params(p: dict) -> SurvivalAgentParams:
    return SurvivalAgentParams(framework=p["framework"], representation=p["representation"], model=p["model"],
                               lr_scale=p["lr_scale"], plays=p["train_plays"] if p["train_plays"] > 1 else 2)


def _test(env: SurvivalEnv, agent, layouts: list[int]) -> dict:
    """Greedy plays (learning off, T = 0) on the test environments; seeds fixed per environment so every
    test point sees the same enemy random streams (common random numbers)."""
    food, outcomes = [], {"all_food": 0, "killed": 0, "starved": 0}
    for k in layouts:
        stats = run_trial(env, agent, trial=0, learning=False, seed=k, options={"layout_seed": k})
        food.append(stats.info["food_eaten"])
        outcomes[stats.info["outcome"]] = outcomes.get(stats.info["outcome"], 0) + 1
    return {"food": float(np.mean(food)), "food_per_env": food, **outcomes}


def run_survival(p: dict, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    """One run of the 4.3.1 protocol for one agent (and, with ``eval_envs``, the 4.3.4 evaluation)."""
    train, test = environment_sets(int(rng.integers(2**31 - 1)), p["train_plays"], p["test_envs"])
    env = SurvivalEnv(p["representation"])
    env.reset(seed=int(rng.integers(2**31 - 1)))
    test_env = SurvivalEnv(p["representation"])
    agent = make_survival_agent(_agent_params(p), env, rng)
    planner = getattr(agent, "planner", None)
    n_tests = (p["train_plays"] // p["test_every"] + 1) if p["test_every"] else 0
    total = p["train_plays"] + n_tests * p["test_envs"] + p["eval_envs"]
    done = 0
    rows, xs, ys = [], [], []

    def do_test(plays):
        nonlocal done
        r = _test(test_env, agent, test)
        xs.append(plays)
        ys.append(r["food"])
        rows.append({"kind": "test", "plays": plays, "food": r["food"], "all_food": r["all_food"],
                     "killed": r["killed"], "starved": r["starved"]})
        done += len(test)
        progress(done, total)

    hyp = []
    for k, layout in enumerate(train):
        if n_tests and k % p["test_every"] == 0:
            do_test(k)
        stats = run_trial(env, agent, trial=k, learning=True, options={"layout_seed": layout})
        row = {"kind": "train", "plays": k + 1, "food": stats.info["food_eaten"], "outcome": stats.info["outcome"],
               "steps": stats.steps, "stuck_steps": agent.explore.boosted}
        if planner is not None:
            h = planner.hypothetical / max(planner.steps, 1)
            hyp.append(h)
            row["hypothetical_per_step"] = h
            if hasattr(planner.model, "pop_errors"):
                row.update({f"model_{k2}": v for k2, v in planner.model.pop_errors().items()})
        rows.append(row)
        done += 1
        progress(done, total)
    if n_tests and len(train) % p["test_every"] == 0:
        do_test(len(train))

    metrics: dict = {}
    if ys:
        metrics["final_food"] = float(np.mean(ys[-3:]))
        metrics["food_auc"] = float(np.mean(ys))
        reached = [x for x, y in zip(xs, ys, strict=True) if y >= 8.0]
        metrics["plays_to_8"] = float(reached[0]) if reached else None
    extra: dict = {"test_plays": xs, "test_food": ys}
    if hyp:
        metrics["hypothetical_per_step_first20"] = float(np.mean(hyp[:20]))
        metrics["hypothetical_per_step_last20"] = float(np.mean(hyp[-20:]))
        extra["hypothetical_per_step"] = hyp
    if p["eval_envs"]:
        ev = evaluate(agent, p["representation"], int(rng.integers(2**31 - 1)), p["eval_envs"],
                      lambda d: progress(done + d, total))
        metrics.update({k: ev[k] for k in ("eval_food", "eval_all_food_pct", "eval_killed_pct",
                                           "eval_starved_pct")})
        extra["eval_histogram_pct"] = ev["histogram_pct"]
        extra["example_play"] = ev["example_play"]
    progress(total, total)
    if p["curve"] == "planning":
        b = p["planning_block"]
        cx = [float(i + b) for i in range(0, len(hyp), b)]
        cy = [float(np.mean(hyp[i:i + b])) for i in range(0, len(hyp), b)]
        return RunResult(cx, cy, metrics, rows, extra)
    return RunResult(xs, ys, metrics, rows, extra)


def evaluate(agent, representation: str, seed: int, n_envs: int, progress=lambda d: None) -> dict:
    """4.3.4: greedy plays on ``n_envs`` fresh random environments; outcome shares and the food histogram.
    The first play is also recorded step by step (``example_play``) for :func:`render_play`."""
    env = SurvivalEnv(representation)
    _, layouts = environment_sets(seed, 0, n_envs)
    food, outcomes = np.zeros(16, dtype=np.int64), {"all_food": 0, "killed": 0, "starved": 0}
    example = []
    for i, k in enumerate(layouts):
        record = None
        if i == 0:
            def record(info):
                example.append(_frame(env))
            env.reset(seed=k, options={"layout_seed": k})
            example.append(_frame(env))
        stats = run_trial(env, agent, trial=0, learning=False, seed=k, options={"layout_seed": k}, on_step=record)
        food[stats.info["food_eaten"]] += 1
        outcomes[stats.info["outcome"]] += 1
        if i % 200 == 0:
            progress(i)
    n = float(n_envs)
    return {"eval_food": float(np.dot(np.arange(16), food) / n),
            "eval_all_food_pct": 100 * outcomes["all_food"] / n, "eval_killed_pct": 100 * outcomes["killed"] / n,
            "eval_starved_pct": 100 * outcomes["starved"] / n, "histogram_pct": (100 * food / n).tolist(),
            "example_play": example}


def _frame(env: SurvivalEnv) -> dict:
    s = env.get_state()
    return {"agent": list(s["agent"]), "enemies": s["enemies"].tolist(), "food": np.argwhere(s["food"]).tolist(),
            "energy": s["energy"], "orientation": s["orientation"], "food_eaten": s["food_eaten"],
            "steps": s["steps"], "outcome": s["outcome"]}


def render_play(frames: list[dict], path: Path, representation: str = "global", n_panels: int = 6) -> Path:
    """A PNG of a play: ``n_panels`` snapshots (rendered by the env's ``render_rgb``) with the agent's path so
    far drawn on each, captioned with step, food and energy."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from connrl.envs.survival import GRID_SIZE, render_rgb

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
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    fig.savefig(tmp, format="png")
    tmp.replace(path)
    plt.close(fig)
    return path


# ------------------------------------------------------------------------------------------------ specs

def _variants(study: int, q_only: bool = False) -> tuple[Variant, ...]:
    out = []
    for base in ("QCON",) if q_only else ("AHCON", "QCON"):
        for ext in ("", "-R", "-M learned", "-M perfect", "-T"):
            fw, _, model = (base + ext).partition(" ")
            label = f"{fw} ({model} model)" if model else fw
            params = {"framework": fw} | ({"model": model} if model else {})
            out.append(Variant(label, params, _THESIS_PLAYS_TO_8.get(label, {}) if study == 2 else {}))
    return tuple(out)


_THESIS_PLAYS_TO_8 = {  # 4.5 table (Study 2, Q-agents): plays to reach 8 food per play
    "QCON": {"plays_to_8": 200}, "QCON-M (learned model)": {"plays_to_8": 140},
    "QCON-M (perfect model)": {"plays_to_8": 95}, "QCON-R": {"plays_to_8": 80}, "QCON-T": {"plays_to_8": 60},
}

_CURVE_QUANTITIES = (
    Quantity("final_food", "mean food per test play, last 3 tests (plays 260-300)", "higher", "4.3"),
    Quantity("food_auc", "mean food per test play over all tests (learning speed)", "higher", "4.4"),
    Quantity("plays_to_8", "first test at which a run reaches 8 food per play", "lower", "4.5"),
)
_PROFILES = {
    "tiny": {"runs": 1, "train_plays": 4, "test_envs": 2, "test_every": 2},
    "quick": {"runs": 2, "train_plays": 100, "test_envs": 20},
    "full": {"runs": 7},
}
_STUDY2 = {**SURVIVAL_PARAMS, "representation": "local", "lr_scale": 2.0}

EXPERIMENTS = [
    ExperimentSpec(
        name="survival-study1", title="Survival, Study 1: global action representation (Fig. 4.3)",
        section="4.3.2", run="connrl.experiments.survival:run_survival", params=SURVIVAL_PARAMS,
        profiles=_PROFILES, variants=_variants(1), quantities=_CURVE_QUANTITIES,
        x_label="plays", y_label="food per test play"),
    ExperimentSpec(
        name="survival-study2", title="Survival, Study 2: local action representation (Fig. 4.4)",
        section="4.3.3", run="connrl.experiments.survival:run_survival", params=_STUDY2,
        profiles=_PROFILES, variants=_variants(2), quantities=_CURVE_QUANTITIES,
        x_label="plays", y_label="food per test play", y_reference={"8 food (4.5 table)": 8.0}),
    ExperimentSpec(
        name="survival-planning", title="Hypothetical actions per step, Study 2 -M agents (Fig. 4.5)",
        section="4.4.3", run="connrl.experiments.survival:run_survival",
        params={**_STUDY2, "curve": "planning"}, profiles=_PROFILES,
        variants=tuple(v for v in _variants(2) if "-M" in v.label),
        quantities=(Quantity("hypothetical_per_step_first20", "hypothetical actions per step, plays 1-20",
                             "higher", "4.4.3"),
                    Quantity("hypothetical_per_step_last20", "hypothetical actions per step, last 20 plays",
                             "lower", "4.4.3")),
        x_label="plays", y_label="hypothetical actions per step", y_reference={"maximum (4 actions)": 4.0}),
    ExperimentSpec(
        name="survival-speedup", title="Study 2 Q-agents: plays to reach 8 food per play (4.5 table)",
        section="4.5", run="connrl.experiments.survival:run_survival", params=_STUDY2, profiles=_PROFILES,
        variants=_variants(2, q_only=True), quantities=_CURVE_QUANTITIES,
        x_label="plays", y_label="food per test play", y_reference={"8 food": 8.0}),
    ExperimentSpec(
        name="survival-eval", title="QCON-T after 300 plays on 8000 random environments (4.3.4)",
        section="4.3.4", run="connrl.experiments.survival:run_survival",
        params={**SURVIVAL_PARAMS, "framework": "QCON-T", "test_every": 0, "eval_envs": 8000},
        profiles={"tiny": {"runs": 1, "train_plays": 3, "eval_envs": 3},
                  "quick": {"runs": 1, "eval_envs": 1000}, "full": {"runs": 7}},
        variants=(Variant("QCON-T", {}, {"eval_food": 12.1, "eval_all_food_pct": 39.9, "eval_killed_pct": 31.9,
                                         "eval_starved_pct": 28.2}),),
        quantities=(Quantity("eval_food", "food per play", "higher", "4.3.4"),
                    Quantity("eval_all_food_pct", "% of plays with all 15 pieces", "higher", "4.3.4"),
                    Quantity("eval_killed_pct", "% of plays killed by an enemy", "lower", "4.3.4"),
                    Quantity("eval_starved_pct", "% of plays that ran out of energy", "lower", "4.3.4")),
        x_label="plays", y_label="food per play"),
]

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
    from connrl.experiments.registry import get_experiment
    from connrl.experiments.runner import load_record, make_jobs

    p = out / name / "summary.json"
    if not p.exists():
        return None, []
    summary = json.loads(p.read_text())
    jobs = make_jobs(get_experiment(name), summary["profile"], summary["runs_per_variant"], summary["base_seed"], out)
    return summary, [r for r in (load_record(j) for j in jobs) if r is not None]


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
    return recs[0]["curve_x"][:n], list(np.mean([r["curve_y"][:n] for r in recs], axis=0))


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
    from connrl.report.page import figure

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
    parts = ["## Chapter 4: the survival task", "",
             "Eight frameworks (3.1) on the survival task of Ch. 4; the -M agents with the learned and the "
             "perfect model (4.2.5). Protocol of 4.3.1; parameters of Table 4.1 (see "
             "`connrl/agents/survival.py`). *final food* is the mean food per test play over the last three "
             "tests (plays 260, 280, 300); *mean food over all tests* is our measure of learning speed; ± is "
             "the standard deviation over runs.", ""]
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
    from connrl.report.page import figure

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
    from connrl.report.page import figure

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
        lines += ["One evaluation play of the first run (`connrl.experiments.survival.render_play`):", "",
                  f"![a survival play](figures/{png.name})", ""]
    return lines
