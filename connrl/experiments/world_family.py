"""Issue 44: the robot world as a family of readings of the text, measured (``connrl world-family``).

The protocol is docs/RECONSTRUCTION.md, "The robot world as a family (issue 44)", committed before the search ran:

1. ``search``: Optuna's TPE over ``SPACE`` (the DP world's open details). A world first passes the Fig. 5.3b caption
   filter (``caption_shares``), then gets 7 no-teaching DP runs at full profile on the development seeds 100-106;
   it is accepted when the mean curve first reaches 2.5 at trial 190-300 and at most 3 runs never do (thesis: 280,
   one run of 7 failing). Never a teaching result.
2. ``recheck``: every accepted world again on seeds 5100-5106; it stays accepted only if it meets the target there.
3. ``predict``: for the worlds accepted twice, and today's world, the teaching and lambda claims of 5.6 and the
   copy bound, as predictions; ``pick`` is the rule fixed before they were seen (the accepted world nearest today's).

Every stage reuses finished run records (an interrupted stage resumes), logs every world in ``out`` as JSON and CSV,
and runs its jobs on the process pool or as Ray tasks (``executor="ray"``, ``address`` of a cluster).
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from connrl.core.params import values_key
from connrl.envs.robot import Layout, RobotSim
from connrl.experiments.robot import BEFORE_44, RobotParams, first_reaching
from connrl.experiments.runner import Job, execute
from connrl.experiments.spec import as_dict, qualified_name
from connrl.experiments.store import load_record
from connrl.storage import atomic_write_text, read_json, strict_json


@dataclass(frozen=True)
class Detail:
    """One open detail of the world: a range [low, high] on a grid of ``step``, or ``choices``."""

    name: str
    low: float = 0.0
    high: float = 0.0
    step: float = 1.0
    choices: tuple = ()

    def span(self) -> float:
        return self.high - self.low


SPACE = (Detail("door_width", 36.0, 72.0, 1.0), Detail("edge_jump", 24.0, 64.0, 1.0),
         Detail("edge_mark", choices=("nearer", "both")), Detail("sonar_origin", choices=("body", "centre")),
         Detail("collision", choices=("cancel", "partial")), Detail("dp_far", 48.0, 96.0, 1.0),
         Detail("dp_lateral", 0.5, 2.0, 0.05), Detail("pass_depth", 0.0, 24.0, 1.0))
# "today's world" of the protocol: the world before issue 44 (the pick is the accepted world nearest it, and it
# is measured beside the family); the default world is now the pick (connrl.envs.robot.constants).
TODAY = dict(BEFORE_44)
SEARCH_SEEDS, RECHECK_SEEDS = tuple(range(100, 107)), tuple(range(5100, 5107))
LEVEL, TARGET_T, T_LOW, T_HIGH, MAX_FAILING = 2.5, 280, 190, 300, 3
BUDGET, STARTUP = 160, 24
CAPTION_SCANS, CAPTION_SHARE = 200, 0.5
REJECTED_LOSS = 5.0
LAMBDA_WORLDS = 6  # the accepted worlds nearest today's that also get the lambda table
_RUN, _COPY = "connrl.experiments.robot:run_robot", "connrl.experiments.robot_bounds:run_copy"
_PARAMS, _COPY_PARAMS = qualified_name(RobotParams), "connrl.experiments.robot_bounds:CopyParams"


def caption_shares(world: dict, scans: int = CAPTION_SCANS) -> tuple[float, float]:
    """Share of noisy scans at L3 and at L4, facing north, showing exactly four door-edge bits (Fig. 5.3b/c)."""
    layout = Layout.load("default")
    if world["door_width"] != layout.doors["A"].width:
        layout = layout.with_door_width(world["door_width"])
    shares = []
    for name in ("L3", "L4"):
        x, y = layout.locations[name][:2]
        sim = RobotSim(layout, np.random.default_rng(0), edge_jump=world["edge_jump"], edge_mark=world["edge_mark"],
                       sonar_origin=world["sonar_origin"])
        sim.place(x, y, 90.0)
        shares.append(sum(int(sim.sense().door_edge.sum()) == 4 for _ in range(scans)) / scans)
    return shares[0], shares[1]


def distance(world: dict) -> float:
    """Distance from today's world: each range's change over its span, plus one per changed choice."""
    return sum((world[d.name] != TODAY[d.name]) if d.choices else abs(world[d.name] - TODAY[d.name]) / d.span()
               for d in SPACE)


def score(curves: list[list[float]], reached: list) -> dict:
    """T (first trial of the mean curve at LEVEL), F (runs never at LEVEL), the loss and the verdict. A diverged run
    (no curve, no ``reached``) counts as failing and stays out of the mean curve."""
    n = max((len(c) for c in curves), default=0)
    whole = [c for c in curves if n and len(c) == n]
    mean = np.mean(np.asarray(whole, dtype=float), axis=0) if whole else np.zeros(0)
    t = _reach(mean, LEVEL)
    failing = sum(r is None for r in reached)
    extra = 0.1 * max(0, failing - 1)
    shortfall = max(0.0, (LEVEL - float(mean.max())) / LEVEL) if whole else 1.0
    # |ln(T/280)| as declared; a world at 2.5 before any learning (T = 0) is scored as at trial 10, not as never
    loss = (abs(math.log(max(t, 10) / TARGET_T)) if t is not None else math.log(T_HIGH / TARGET_T) + shortfall) + extra
    return {"T": t, "F": failing, "loss": round(float(loss), 4), "mean_curve": [round(float(v), 4) for v in mean],
            "accepted": t is not None and T_LOW <= t <= T_HIGH and failing <= MAX_FAILING}


def _reach(mean, level: float) -> int | None:
    """First test trial (a test every 10 trials, from trial 0) at which the mean curve reaches ``level``."""
    return first_reaching(range(0, 10 * len(mean), 10), mean, level)


def _jobs(out: Path, world: dict, seeds, label: str, trials: int, extra: dict | None = None,
          copy: bool = False) -> list[Job]:
    params = as_dict(RobotParams(lessons=0, trials=trials, **world)) | (extra or {})
    if copy:
        params |= {"policy": "copy", "copy_epochs": 200}
    root = out / "runs" / values_key(RobotParams, params)  # as run_key: a new field moves no folder
    return [Job("world-family", _COPY if copy else _RUN, label, params, s, str(root / f"seed-{s}"),
                _COPY_PARAMS if copy else _PARAMS) for s in seeds]


def run_jobs(jobs: list[Job], workers: int, executor: str, address: str | None, show: bool) -> dict[str, dict]:
    """The records of ``jobs`` by path: stored ones reused (a damaged one is redone), the rest run."""
    done, todo = {}, []
    jobs = list({j.path: j for j in jobs}.values())  # two proposals of one batch may be the same world
    for job in jobs:
        rec, _damage = load_record(job.path, job)
        if rec is None:
            todo.append(job)
        else:
            done[job.path] = rec
    if todo:
        for _ in execute(todo, min(workers, len(todo)), show, "world-family", executor, address):
            pass  # execute writes each run's records
        for job in todo:
            rec, damage = load_record(job.path, job)
            if rec is None:
                raise RuntimeError(f"run {job.path} left no record ({damage or 'missing'})")
            done[job.path] = rec
    return done


def evaluate_worlds(out: Path, worlds: list[dict], seeds, trials: int, **run) -> list[dict]:
    """The no-teaching target for each world (the caption filter first)."""
    rows, jobs = [], {}
    for i, w in enumerate(worlds):
        l3, l4 = caption_shares(w)
        ok = min(l3, l4) >= CAPTION_SHARE
        rows.append({"world": w, "caption_L3": l3, "caption_L4": l4, "caption_ok": ok})
        if ok:
            jobs[i] = _jobs(out, w, seeds, "no teaching", trials)
    recs = run_jobs([j for js in jobs.values() for j in js], **run) if jobs else {}
    for i, row in enumerate(rows):
        if i not in jobs:
            row |= {"T": None, "F": None, "loss": REJECTED_LOSS, "accepted": False, "mean_curve": []}
            continue
        rs = [recs[j.path] for j in jobs[i]]
        row |= score([r["curve_y"] for r in rs], [r["metrics"].get(f"trials_to_{LEVEL:g}") for r in rs])
    return rows


# ------------------------------------------------------------------------------------------------ stages

def _study(done: list[dict], seed: int):
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    dists = {d.name: (optuna.distributions.CategoricalDistribution(list(d.choices)) if d.choices else
                      optuna.distributions.FloatDistribution(d.low, d.high, step=d.step)) for d in SPACE}
    sampler = optuna.samplers.TPESampler(seed=seed + len(done), n_startup_trials=STARTUP, multivariate=True,
                                         constant_liar=True)
    study = optuna.create_study(direction="minimize", sampler=sampler)
    for t in done:
        study.add_trial(optuna.trial.create_trial(params=t["world"], distributions=dists, value=t["loss"]))
    return study, dists


def search(out: Path, budget: int = BUDGET, trials: int = 300, seed: int = 0, workers: int = 2,
           executor: str = "process", address: str | None = None, show: bool = True, log=print) -> list[dict]:
    """Stage 1: the TPE search, resumed from ``out/search.json``; returns every world's row. ``trials``: per run
    (300, the protocol's; fewer only for a smoke test). Worlds are asked for in batches of the worker count (at
    least 2) fixed when the search starts and kept in the log, so a resume on another machine asks the same worlds."""
    path = out / "search.json"
    log_doc = read_json(path) if path.exists() else {"trials": trials, "batch": max(2, workers), "worlds": []}
    if _trials(log_doc) != trials:
        raise ValueError(f"{path} is a search with {_trials(log_doc)} trials per run, not {trials}: resume it with "
                         f"the same --trials or use another --out")
    done, batch_size = log_doc["worlds"], log_doc.get("batch", 2)  # logs before the key: batches of 2
    run = {"workers": workers, "executor": executor, "address": address, "show": show}
    while len(done) < budget:
        study, dists = _study(done, seed)
        batch = [study.ask(dists) for _ in range(min(batch_size, budget - len(done)))]
        worlds = [{d.name: _plain(t.params[d.name]) for d in SPACE} for t in batch]
        for row in evaluate_worlds(out, worlds, SEARCH_SEEDS, trials, **run):
            row["number"] = len(done)
            done.append(row)
            log(_line(row))
        _write(out, "search", done, trials, batch_size)
    return done


def _trials(log_doc: dict) -> int:
    return log_doc.get("trials", 300)  # logs written before --trials existed are the protocol's 300


def recheck(out: Path, **run) -> list[dict]:
    """Stage 2: the accepted worlds on seeds 5100-5106."""
    first = read_json(out / "search.json")
    accepted = [r for r in first["worlds"] if r["accepted"]]
    rows = evaluate_worlds(out, [r["world"] for r in accepted], RECHECK_SEEDS, _trials(first), **run)
    for row, src in zip(rows, accepted, strict=True):
        row["number"] = src["number"]
    _write(out, "recheck", rows, _trials(first))
    return rows


PREDICTIONS = (("3 lessons", {"lessons": 3}, False), ("10 lessons", {"lessons": 10}, False),
               ("copy 10 lessons", {"lessons": 10}, True))
LAMBDAS = (("10 lessons, lambda=0", {"lessons": 10, "lam": 0.0}),
           ("10 lessons, lambda=0.3", {"lessons": 10, "lam": 0.3}))


def predict(out: Path, **run) -> dict:
    """Stage 3: teaching, lambda and copy-bound predictions for the worlds accepted twice and today's; the pick."""
    again = read_json(out / "recheck.json")
    twice, trials = [r for r in again["worlds"] if r["accepted"]], _trials(again)
    worlds = [{"number": "today", "world": dict(TODAY)}] + [{"number": r["number"], "world": r["world"]} for r in twice]
    near = sorted(twice, key=lambda r: (distance(r["world"]), r["loss"]))[:LAMBDA_WORLDS]
    with_lambda = {"today"} | {r["number"] for r in near}
    plan = []
    for w in worlds:
        cases = [*PREDICTIONS, *((label, extra, False) for label, extra in LAMBDAS if w["number"] in with_lambda)]
        if w["number"] == "today":
            cases.insert(0, ("no teaching", {}, False))
        plan += [(w, label, _jobs(out, w["world"], RECHECK_SEEDS, label, trials, extra, copy))
                 for label, extra, copy in cases]
    recs = run_jobs([j for *_, jobs in plan for j in jobs], **run)
    for w, label, jobs in plan:
        rs = [recs[j.path] for j in jobs]
        w.setdefault("cases", {})[label] = _case(rs, copy=label.startswith("copy"))
    pick = min(twice, key=lambda r: (distance(r["world"]), r["loss"]), default=None)
    doc = {"trials": trials, "worlds": worlds, "pick": None if pick is None else pick["number"],
           "rule": "the world accepted twice nearest today's (docs/RECONSTRUCTION.md, issue 44)"}
    atomic_write_text(out / "predictions.json", strict_json(doc, indent=1))
    return doc


def _case(rs: list[dict], copy: bool) -> dict:
    if copy:
        return {"performance": float(np.mean([r["metrics"]["performance"] for r in rs]))}
    mean = np.mean([r["curve_y"] for r in rs if r["curve_y"]], axis=0)  # a diverged run has no curve
    out = {"mean_curve": [round(float(v), 4) for v in mean]}
    for level in (2.5, 5.0):
        out[f"T{level:g}"] = _reach(mean, level)
        out[f"runs_to_{level:g}"] = [r["metrics"].get(f"trials_to_{level:g}") for r in rs]
    return out


def _plain(v):
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else v


def _line(row: dict) -> str:
    w = row["world"]
    what = ("caption filter: no" if not row["caption_ok"] else
            f"T {row['T'] if row['T'] is not None else '-'}, F {row['F']}/7, loss {row['loss']:.3f}"
            f"{', ACCEPTED' if row['accepted'] else ''}")
    return (f"world {row['number']:3d}: door {w['door_width']:g}, edge {w['edge_jump']:g} {w['edge_mark']}, "
            f"sonar {w['sonar_origin']}, {w['collision']}, far {w['dp_far']:g}, lateral {w['dp_lateral']:g}, "
            f"pass {w['pass_depth']:g} -> {what}")


COLUMNS = ("number", *(d.name for d in SPACE), "caption_L3", "caption_L4", "caption_ok", "T", "F", "loss", "accepted")


def _write(out: Path, stage: str, rows: list[dict], trials: int, batch: int | None = None) -> None:
    """``stage``.json (the log the next stage and the report read) and ``stage``.csv (one row a world)."""
    doc = {"stage": stage, "trials": trials} | ({"batch": batch} if batch else {}) | {"worlds": rows}
    atomic_write_text(out / f"{stage}.json", strict_json(doc, indent=1))
    buf = io.StringIO()
    writer = csv.DictWriter(buf, COLUMNS, extrasaction="ignore")
    writer.writeheader()
    for r in rows:
        writer.writerow(r | r["world"])
    atomic_write_text(out / f"{stage}.csv", buf.getvalue())
