"""docs/RESULTS.md: the door-passing calibration of issue 12 -- the copy bound's table and generated sentences on the
calibration, each calibrated change alone, the replay order and the fresh seeds (docs/RECONSTRUCTION.md, "Calibration
of door passing", says how they were chosen)."""

from __future__ import annotations

import numpy as np

from connrl.experiments.robot import SPEC_DP, RobotParams, first_reaching
from connrl.experiments.spec import ExperimentSpec
from connrl.report.page import fixed

WIDTHS = (36, 42, 48)


def copy_table(spec: ExperimentSpec, summary: dict) -> list[str]:
    """One row per copy (and the teacher): test performance, passes of the 50 tests, agreement on taught states."""
    lines = ["| variant | performance (reinforcement/step) | passes of 50 | agreement on taught states |",
             "|---|---|---|---|"]
    for v in spec.variants:
        qs = summary["variants"].get(v.label, {}).get("quantities")
        if qs is None:
            continue
        lines.append(f"| {v.label} | {fixed(qs['performance']['mean'])} | {fixed(qs['passes']['mean'], 1)} | "
                     f"{fixed(qs['agreement']['mean'])} |")
    return lines + [""]


def _at(curves, key, trial):
    xs, ys, _ = curves[key]
    xs = list(xs)
    return float(ys[xs.index(trial)]) if trial in xs else float("nan")


def _reach(curves, key, level):
    xs, ys, _ = curves[key]
    n = first_reaching(list(xs), list(ys), level)
    return "not reached" if n is None else f"trial {n:g}"


TEACH = [("robot-teaching-dp", v) for v in ("no teaching", "3 lessons", "10 lessons")]


def dp_notes(curves, copy_summary: dict | None, seeds: dict[str, str]) -> list[str]:
    """Generated paragraphs (each only when its experiments were run)."""
    return [*_calibration(curves, seeds), *_copy_bound(curves, copy_summary, seeds), *_changes(curves, seeds),
            *_order(curves, seeds), *_fresh(curves, seeds)]


def _calibration(curves, seeds) -> list[str]:
    out = []
    cal = [("robot-dp-calibration", f"{w}-in doors, no teaching") for w in WIDTHS]
    if all(k in curves for k in cal):
        at280 = {w: _at(curves, k, 280) for w, k in zip(WIDTHS, cal, strict=True)}
        pick = min(WIDTHS, key=lambda w: abs(at280[w] - 2.5))
        out += [f"**Calibration** (`robot-dp-calibration`, development seeds {seeds['robot-dp-calibration']}): the "
                "criterion is the mean no-teaching curve at trial 280, where the thesis's reaches 2.5 (Fig. 5.4a, "
                "5.6), among door widths the text's \"narrow\" allows (at most twice the 24-in body). At trial 280: "
                + "; ".join(f"{w}-in doors {at280[w]:.2f}" for w in WIDTHS) + f". The criterion picks {pick} in; "
                f"the default is {RobotParams.door_width:g} in. The door-edge threshold was fixed beforehand from the "
                "text alone (Fig. 5.3b, `python scripts/dp_calibration/edge_jump.py`).", ""]
    return out


def _copy_bound(curves, copy_summary, seeds) -> list[str]:
    out: list[str] = []
    teach = TEACH
    if copy_summary is not None and all(k in curves for k in teach):
        q = {v: copy_summary["variants"][v]["quantities"] for v in copy_summary["variants"]}
        copy10 = q["copy 10 lessons"]["performance"]["mean"]
        rl10 = _at(curves, teach[2], 10)
        out += [f"**Copy bound** (`robot-dp-copy`, seeds {seeds['robot-dp-copy']}, the same test tasks as "
                "robot-teaching-dp), reinforcement per step of the greedy policies (" + "; ".join(
                    f"{v} {q[v]['performance']['mean']:.2f} ({q[v]['passes']['mean']:.1f} passes of 50)"
                    for v in ("copy 3 lessons", "copy 10 lessons", "copy 100 demonstrations", "scripted teacher")
                    if v in q) + f"). QCON-T with the 10 lessons scores {rl10:.2f} at trial 10 (thesis 2.5). "
                + ("Even a copy of the 10 lessons stays below 2.5, so in this reconstruction the 10 lessons alone "
                   "do not carry the thesis's trial-10 performance; " if copy10 < 2.5 else
                   "A copy of the 10 lessons reaches 2.5, so the lessons carry the thesis's trial-10 performance; ")
                + ("the 100-demonstration copy shows the inputs carry more." if
                   q.get("copy 100 demonstrations", {}).get("performance", {}).get("mean", -1e9) > copy10 else "")]
        use = ("robot-dp-lesson-use", "100 lessons")
        if use in curves and "copy 100 demonstrations" in q:
            copy100 = q["copy 100 demonstrations"]["performance"]["mean"]
            rl = {t: _at(curves, use, t) for t in (10, 50)}
            verdict = (": what limits early learning here is how replay turns positive examples into a policy (it "
                       "learns the taught action's value only, 3.7, 5.4.3), not what the lessons hold."
                       if rl[10] < copy100 - 1.0 else ".")
            out[-1] += (f" One change isolates the rest: QCON-T replaying those same 100 demonstrations "
                        f"(`robot-dp-lesson-use`, seeds {seeds['robot-dp-lesson-use']}) scores {rl[10]:.2f} at "
                        f"trial 10 and {rl[50]:.2f} at trial 50 (2.5 at {_reach(curves, use, 2.5)}), against "
                        f"{copy100:.2f} for their copy{verdict}")
        out.append("")
    return out


def _changes(curves, seeds) -> list[str]:
    out: list[str] = []
    teach = TEACH
    geo = {label: [("robot-dp-geometry", f"{label}, {n} lessons") for n in (0, 10)]
           for label in (SPEC_DP, "36-in doors only", "24-in edges only")}
    if all(k in curves for ks in geo.values() for k in ks) and all(k in curves for k in teach):
        rows = {**geo, "calibrated (48-in doors, 44-in edges)": [teach[0], teach[2]]}
        out += [f"**Each calibrated change alone** (`robot-dp-geometry`, seeds {seeds['robot-dp-geometry']}; "
                "calibrated = robot-teaching-dp): mean-curve trials to 2.5 with 10 lessons / without teaching, and "
                "final performance with 10 lessons: " + "; ".join(
                    f"{label}: {_reach(curves, ks[1], 2.5)} / {_reach(curves, ks[0], 2.5)}, "
                    f"{float(np.mean(curves[ks[1]][1][-3:])):.2f}" for label, ks in rows.items()) + ".", ""]
    return out


def _order(curves, seeds) -> list[str]:
    out: list[str] = []
    order = [("robot-dp-replay-order", f"{n} lessons, {o}") for n in (3, 10) for o in ("after", "shuffled")]
    if all(k in curves for k in order):
        out += [f"**Replay order** (`robot-dp-replay-order`, seeds {seeds['robot-dp-replay-order']}): mean-curve "
                "trials to 2.5 (final performance): " + "; ".join(
                    f"{k[1]}: {_reach(curves, k, 2.5)} ({float(np.mean(curves[k][1][-3:])):.2f})" for k in order)
                + ". The default stays \"after\" (chosen on seeds 100-106, docs/RECONSTRUCTION.md).", ""]
    return out


def _fresh(curves, seeds) -> list[str]:
    out: list[str] = []
    fresh = {v: ("robot-dp-fresh", v) for v in ("no teaching", "3 lessons", "10 lessons", "10 lessons, lambda=0",
                                                "10 lessons, lambda=0.3")}
    if all(k in curves for k in fresh.values()):
        lam = [fresh["10 lessons, lambda=0"], fresh["10 lessons, lambda=0.3"], fresh["10 lessons"]]
        firsts = [first_reaching(list(curves[k][0]), list(curves[k][1]), 5.0) for k in lam]
        means = [float(np.mean(curves[k][1])) for k in lam]
        ordered = means[0] < means[1] < means[2]
        out += [f"**Fresh seeds** (`robot-dp-fresh`, seeds {seeds['robot-dp-fresh']}, never used in development): "
                "mean-curve trials to 2.5 without teaching / 3 / 10 lessons (thesis 280 / 20 / 10): " + " / ".join(
                    _reach(curves, fresh[v], 2.5) for v in ("no teaching", "3 lessons", "10 lessons")) +
                "; to 5 with 10 lessons at lambda 0 / 0.3 / 0.7 (thesis 280 / 140 / 65): " + " / ".join(
                    _reach(curves, k, 5.0) for k in lam) + ". The lambda ordering by mean performance over the "
                f"run (0 < 0.3 < 0.7) {'holds' if ordered else 'does not hold'}: "
                + (" < " if ordered else ", ").join(f"{m:.2f}" for m in means)
                + ("." if None not in firsts else "; a curve that never reaches 5 has no trial count."), ""]
    return out
