"""``connrl tune ENV``: a search over an agent's settings on seeds of its own (RL Zoo's ``--optimize``).

Each trial draws settings from the search space, trains one agent per tuning seed for ``steps`` steps and scores it by
the mean greedy return over ``eval_episodes`` episodes on evaluation seeds (``EVAL_SEED`` on); a trial's score is the
mean over its seeds. The tuning seeds (default 1000, 1001) are apart from the seeds connrl's own measurements report
(0-2, development 100-119, fresh 200-206), so a tuned setting is checked on seeds it never saw. Samplers: ``random``
(built in, seeded: trial k's settings are the same in every run, and no setting is tried twice: where the space is
a few choices, its grid in a shuffled order; ``planned``) and ``tpe`` (Optuna's, the ``tune`` extra). ``workers``
trials run at once in processes (random sampler); the median pruner stops a trial whose running mean after a seed is
below the median of the whole (not pruned) trials' after that seed (``median_thresholds``).

Files in ``out``: ``trials.csv`` (one row per finished trial, rewritten atomically after each: an interrupted search
resumes where it stopped), ``study.json`` (what was searched: a resumed search must search the same) and
``best.yml`` (the best whole trial as a settings file entry: ``connrl train ENV --hyperparams best.yml``; its
``n_timesteps`` is the training budget asked for, not the search's per-agent budget, which its comment states).
"""

from __future__ import annotations

import csv
import io
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from connrl.storage import FileError, atomic_write_text, read_json, read_limited_text, shown

EVAL_SEED = 2_000_000
DEFAULT_SPACE = ("lr=0.01:0.2:log", "hidden=8,16,32", "lam=0.3,0.7,0.9", "lessons_per_trial=10,20,40")


@dataclass(frozen=True)
class Dimension:
    """One searched option: ``choices``, or a range [low, high] (``log``: log-uniform; ints when both ends are)."""

    name: str
    choices: tuple | None = None
    low: float | None = None
    high: float | None = None
    log: bool = False

    @property
    def integer(self) -> bool:
        return self.choices is None and isinstance(self.low, int) and isinstance(self.high, int)

    def sample(self, rng: np.random.Generator):
        if self.choices is not None:
            return self.choices[int(rng.integers(len(self.choices)))]
        u = rng.random()
        if self.log:
            v = math.exp(math.log(self.low) + u * (math.log(self.high) - math.log(self.low)))
        else:
            v = self.low + u * (self.high - self.low)
        v = int(round(v)) if self.integer else float(f"{v:.4g}")
        return min(max(v, self.low), self.high)  # rounding must not leave the range asked for

    def holds(self, v) -> bool:
        """Whether ``v`` is a value this dimension can give (a resumed trial's parameter is checked so)."""
        if self.choices is not None:
            return any(v == c and type(v) is type(c) for c in self.choices)
        if isinstance(v, bool) or not isinstance(v, int | float):
            return False
        if isinstance(v, int) and v.bit_length() > 63 or isinstance(v, float) and not math.isfinite(v):
            return False
        return self.low <= v <= self.high and (not self.integer or isinstance(v, int))

    def describe(self) -> str:
        if self.choices is not None:
            return ",".join(json.dumps(c) for c in self.choices)
        return f"{self.low}:{self.high}" + (":log" if self.log else "")


def parse_dimension(text: str) -> Dimension:
    """``name=a,b,c`` (choices, JSON values), ``name=low:high`` or ``name=low:high:log``; ValueError in one line."""
    from connrl.own.api import AgentOptions

    name, sep, spec = text.partition("=")
    allowed = list(AgentOptions.__dataclass_fields__)
    if not sep or not spec:
        raise ValueError(f"--space expects NAME=a,b,c or NAME=low:high[:log], got {text!r}")
    if name not in allowed:
        raise ValueError(f"--space: unknown option {name!r}; allowed: {', '.join(allowed)}")

    def value(s: str):
        try:
            return json.loads(s)
        except json.JSONDecodeError:
            return s

    if ":" in spec and "," not in spec:
        parts = spec.split(":")
        log = len(parts) == 3 and parts[2] == "log"
        if len(parts) not in (2, 3) or len(parts) == 3 and not log:
            raise ValueError(f"--space {name}: a range is low:high or low:high:log, got {spec!r}")
        low, high = value(parts[0]), value(parts[1])
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (low, high)) or not low < high:
            raise ValueError(f"--space {name}: a range needs two numbers low < high, got {spec!r}")
        if log and low <= 0:
            raise ValueError(f"--space {name}: a log range needs low > 0, got {spec!r}")
        if not isinstance(getattr(AgentOptions(), name), int):  # lam=0:1 is a range of numbers, not of 0 and 1
            low, high = float(low), float(high)
        return Dimension(name, low=low, high=high, log=log)
    return Dimension(name, choices=tuple(value(s) for s in spec.split(",")))


MAX_GRID = 100_000  # combinations beyond which a finite space is drawn from, not enumerated
MAX_INT_GRID = 256  # whole-number ranges up to this many values count as choices


def grid_values(d: Dimension) -> tuple | None:
    """A dimension's values when they are few enough to enumerate: its choices, or a short whole-number range
    (not a log one: enumerated, its values would be drawn evenly)."""
    if d.choices is not None:
        return d.choices
    if d.integer and not d.log and d.high - d.low < MAX_INT_GRID:
        return tuple(range(d.low, d.high + 1))
    return None


def planned(space: list[Dimension], trials: int, seed: int) -> list[dict]:
    """The settings of trials 0, 1, ..., none repeated. Where every option has few values and their combinations
    are at most ``MAX_GRID``, the grid in one seeded shuffled order, its first ``trials`` (all of it when it is
    smaller: a search never tries a setting twice); otherwise seeded draws, a repeat drawn again. Either way trial k's
    settings do not depend on how many trials are asked: a resumed or extended search draws the same."""
    values = [grid_values(d) for d in space]
    size = math.prod(len(v) for v in values) if all(v is not None for v in values) else None
    rng = np.random.default_rng(seed)
    if size is not None and size <= MAX_GRID:
        order = rng.permutation(size)[:trials]
        out = []
        for i in order.tolist():
            params = {}
            for d, vs in zip(reversed(space), reversed(values), strict=True):  # mixed radix, last option fastest
                i, j = divmod(i, len(vs))
                params[d.name] = vs[j]
            out.append({d.name: params[d.name] for d in space})
        return out
    out, seen = [], set()
    while len(out) < trials:
        for _ in range(1000):
            params = {d.name: d.sample(rng) for d in space}
            key = json.dumps(params, sort_keys=True)
            if key not in seen:
                break
        seen.add(key)
        out.append(params)
    return out


def check_space(space: list[Dimension], fixed: dict) -> None:
    """Every option a trial could draw must be valid with the fixed ones: checked on the ranges' ends and every
    choice before any training."""
    from connrl.own.api import options_from

    for d in space:
        for v in d.choices if d.choices is not None else (d.low, d.high):
            try:
                options_from({**fixed, d.name: v})
            except (ValueError, TypeError) as exc:
                raise ValueError(f"--space {d.name}: {exc}") from None


def score(env_fn, kind: str, options: dict, seeds: list[int], steps: int, eval_episodes: int,
          prune_below: tuple = ()) -> list[float]:
    """Mean greedy return over ``eval_episodes`` evaluation episodes of one agent per seed, each trained ``steps``
    steps; a diverged agent scores -inf. The trial is pruned (its later seeds not trained) when its running mean after
    seed j is below ``prune_below[j]``: fewer scores than seeds mark a pruned trial."""
    from connrl.own.api import evaluate, make_agent

    out = []
    for j, seed in enumerate(seeds):
        agent = make_agent(env_fn(), kind, seed=seed, **options).learn(steps)
        if agent.divergence():
            out.append(-math.inf)
        else:
            out.append(float(np.mean(evaluate(agent, env_fn(), eval_episodes, seed=EVAL_SEED))))
        if j < len(seeds) - 1 and j < len(prune_below) and float(np.mean(out)) < prune_below[j]:
            break
    return out


PRUNE_AFTER = 4  # finished trials the median pruner needs before it prunes


def median_thresholds(done: list[dict], n_seeds: int) -> tuple:
    """The median pruner's bars: after seed j (all but the last), the median running mean of the whole (not pruned)
    trials after seed j, once at least ``PRUNE_AFTER`` are whole (Optuna's MedianPruner, which reads completed trials
    only, over seeds instead of steps)."""
    whole = [t for t in done if len(t["scores"]) == n_seeds]
    if len(whole) < PRUNE_AFTER:
        return ()
    return tuple(float(np.median([np.mean(t["scores"][:j + 1]) for t in whole])) for j in range(n_seeds - 1))


def run_search(env_fn, study: dict, space: list[Dimension], out: Path, sampler: str = "random",
               progress=print, workers: int = 1, pruner: str = "none") -> list[dict]:
    """Run (or resume) the search ``study`` describes; returns the finished trials, best first (a pruned trial
    after every whole one). ``workers`` > 1 runs that many trials at once in processes (``env_fn`` must then be
    picklable, e.g. a ``functools.partial``); with the median pruner their bars depend on which trials finished
    first, so such a search is not repeatable to the trial."""
    done = _resume(study, space, out)
    optuna_study = _optuna_study(space, done, study["seed"]) if sampler == "tpe" else None  # Optuna missing:
    atomic_write_text(out / "study.json", json.dumps(study, indent=1) + "\n")  # refused before it is written
    plan = planned(space, study["trials"], study["seed"]) if optuna_study is None else None
    total = study["trials"] if plan is None else len(plan)
    if plan is not None and len(plan) < study["trials"]:
        progress(f"the space holds {len(plan)} settings: {len(plan)} trials, each setting once")

    def submit(run, k):
        if plan is not None:
            params, trial = plan[k], None
        else:
            trial = optuna_study.ask()
            params = {d.name: _suggest(trial, d) for d in space}
        bars = median_thresholds(done, len(study["seeds"])) if pruner == "median" else ()
        return run(score, env_fn, study["agent"], {**study["fixed"], **params}, study["seeds"], study["steps"],
                   study["eval_episodes"], bars), (k, params, trial, time.perf_counter())

    def finish(scores, k, params, trial, t0):
        mean = float(np.mean(scores))
        if optuna_study is not None:
            optuna_study.tell(trial, mean if math.isfinite(mean) else -1e300)
        done.append({"trial": k, "params": params, "scores": scores, "mean": mean,
                     "seconds": round(time.perf_counter() - t0, 2)})
        done.sort(key=lambda t: t["trial"])
        _write_trials(out / "trials.csv", _whole_prefix(done))
        pruned = f" (pruned after {len(scores)} of {len(study['seeds'])} seeds)" if len(scores) < len(
            study["seeds"]) else ""
        progress(f"trial {k + 1}/{total}: {json.dumps(params)} -> mean greedy return {mean:.2f} "
                 f"({', '.join(f'{s:.1f}' for s in scores)}){pruned}")

    todo = list(range(len(done), total))
    if workers <= 1 or optuna_study is not None:
        for k in todo:
            _serial(submit, finish, k)
    else:
        _parallel(submit, finish, todo, workers)
    whole = [t for t in done if len(t["scores"]) == len(study["seeds"])]
    return sorted(whole, key=lambda t: -t["mean"]) + [t for t in done if t not in whole]


def _serial(submit, finish, k) -> None:
    scores, meta = submit(lambda f, *a: f(*a), k)
    finish(scores, *meta)


def _parallel(submit, finish, todo: list[int], workers: int) -> None:
    """Trials ``todo`` in a pool of ``workers`` fresh (spawned) processes, at most that many at a time; every trial
    that finished is handed to ``finish`` before an error or Ctrl-C ends the search (trials.csv keeps those up to the
    first one unfinished), and the workers are then ended, not waited for (the pruner's bars follow the trials as
    they finish)."""
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    try:
        waiting, queue = {}, list(todo)
        while queue or waiting:
            while queue and len(waiting) < workers:
                future, meta = submit(pool.submit, queue.pop(0))
                waiting[future] = meta
            finished, _ = wait(waiting, return_when=FIRST_COMPLETED)
            failed = [f for f in finished if f.exception() is not None]
            for future in sorted(set(finished) - set(failed), key=lambda f: waiting[f][0]):
                finish(future.result(), *waiting.pop(future))
            if failed:
                raise failed[0].exception()
    except BaseException:
        for process in list(getattr(pool, "_processes", {}).values()):
            process.terminate()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()


def _whole_prefix(done: list[dict]) -> list[dict]:
    """The finished trials 0, 1, ... up to the first one still running (trials.csv holds a numbered prefix: a
    resumed search redoes what follows it)."""
    out = []
    for t in done:
        if t["trial"] != len(out):
            break
        out.append(t)
    return out


def _resume(study: dict, space: list[Dimension], out: Path) -> list[dict]:
    """The trials a previous run of this search finished; ValueError where the folder holds another search."""
    out.mkdir(parents=True, exist_ok=True)
    meta, trials_file = out / "study.json", out / "trials.csv"
    if meta.exists():
        try:
            old = read_json(meta, "study file", max_bytes=MAX_STUDY_BYTES)
        except FileError as exc:
            raise ValueError(f"{exc}; remove the folder {out} to start over") from None
        if not isinstance(old, dict) or {**old, "trials": None} != {**study, "trials": None}:  # more trials may
            raise ValueError(f"{out} holds another search ({meta} differs: env, agent, steps, seeds, space, sampler "
                             "or pruner, or it was drawn by an earlier connrl); choose another --out or remove that "
                             "folder")  # more trials may be asked of a search
    elif trials_file.exists():
        raise ValueError(f"{trials_file} has no study.json beside it, so what it searched is unknown; remove the "
                         f"folder {out} to start over")
    return read_trials(trials_file, space) if trials_file.exists() else []


def _optuna_study(space: list[Dimension], done: list[dict], seed: int):
    try:
        import optuna
    except ImportError:
        raise ValueError("--sampler tpe needs Optuna: pip install 'connrl[tune]' (or --sampler random)") from None
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    # seeded past the trials done: a resumed search would otherwise draw its first settings again
    study = optuna.create_study(direction="maximize", sampler=optuna.samplers.TPESampler(seed=seed + len(done)))
    dists = {d.name: _distribution(optuna, d) for d in space}
    for t in done:  # a resumed search tells the sampler what it already knows
        value = t["mean"] if math.isfinite(t["mean"]) else -1e300
        study.add_trial(optuna.trial.create_trial(params=t["params"], distributions=dists, value=value))
    return study


def _distribution(optuna, d: Dimension):
    if d.choices is not None:
        return optuna.distributions.CategoricalDistribution(list(d.choices))
    if d.integer:
        return optuna.distributions.IntDistribution(d.low, d.high, log=d.log)
    return optuna.distributions.FloatDistribution(float(d.low), float(d.high), log=d.log)


def _suggest(trial, d: Dimension):
    if d.choices is not None:
        return trial.suggest_categorical(d.name, list(d.choices))
    if d.integer:
        return trial.suggest_int(d.name, d.low, d.high, log=d.log)
    return trial.suggest_float(d.name, float(d.low), float(d.high), log=d.log)


TRIAL_COLUMNS = ("trial", "params", "scores", "mean", "seconds")
MAX_STUDY_BYTES = 16 * 2**20  # study.json and trials.csv: a few hundred bytes a trial
MAX_SCORE = 1e15  # a mean greedy return beyond this is not one a trial wrote


def _write_trials(path: Path, trials: list[dict]) -> None:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(TRIAL_COLUMNS)
    for t in trials:
        w.writerow([t["trial"], json.dumps(t["params"]), json.dumps([s if math.isfinite(s) else None
                                                                     for s in t["scores"]]),
                    f"{t['mean']:.6g}", t["seconds"]])
    atomic_write_text(path, buf.getvalue())


def read_trials(path: Path, space: list[Dimension] | None = None) -> list[dict]:
    """The finished trials of a trials.csv (read through ``connrl.storage.read_limited``), every cell checked: trials
    numbered 0, 1, ...; parameters a JSON object of the searched options (within ``space`` when given); scores finite
    numbers or null (a diverged agent); the mean the scores' mean (so a forged mean cannot win); seconds >= 0.
    ValueError in one line naming the file and the row otherwise."""
    try:
        rows = list(csv.reader(io.StringIO(read_limited_text(path, MAX_STUDY_BYTES, "trials file"))))
        if not rows or tuple(rows[0]) != TRIAL_COLUMNS:
            raise ValueError("its header is not " + ",".join(TRIAL_COLUMNS))
        names = {d.name: d for d in space} if space is not None else None
        trials = []
        for k, r in enumerate(rows[1:]):
            where = f"row {k + 2}"
            if len(r) != len(TRIAL_COLUMNS):
                raise ValueError(f"{where} has {len(r)} cells, not {len(TRIAL_COLUMNS)}")
            if r[0] != str(k):
                raise ValueError(f"{where} is not trial {k}")
            params, raw_scores = json.loads(r[1]), json.loads(r[2])
            if not isinstance(params, dict) or (names is not None and set(params) != set(names)):
                raise ValueError(f"{where}: its parameters are not the searched options")
            for name, v in params.items():
                if names is not None and not names[name].holds(v):
                    raise ValueError(f"{where}: {name} = {shown(v)} is outside the searched space")
            if not isinstance(raw_scores, list) or not raw_scores or not all(
                    x is None or (isinstance(x, float) and abs(x) <= MAX_SCORE) for x in raw_scores):
                raise ValueError(f"{where}: its scores must be a list of numbers within ±{MAX_SCORE:.0e} (written "
                                 "with a decimal point) or null")
            scores = [-math.inf if x is None else x for x in raw_scores]
            mean = -math.inf if None in raw_scores else math.fsum(scores) / len(scores)  # finite: scores bounded
            stated = float(r[3])
            if not (stated == mean or (math.isfinite(stated) and abs(stated - mean) <= 1e-5 * max(1.0, abs(mean)))):
                raise ValueError(f"{where}: its mean {r[3][:40]!r} is not the mean of its scores")
            seconds = float(r[4])  # ValueError for a string
            if not (math.isfinite(seconds) and seconds >= 0):
                raise ValueError(f"{where}: seconds is {r[4][:40]!r}; it must be a finite number >= 0")
            trials.append({"trial": k, "params": params, "scores": scores, "mean": mean, "seconds": seconds})
        return trials
    except FileError as exc:
        raise ValueError(f"{exc}; remove it to start the search over") from None
    except (ValueError, RecursionError, OverflowError, csv.Error) as exc:  # a JSON error is a ValueError
        raise ValueError(f"{path}: is not a connrl trials file ({str(exc).splitlines()[0][:200]}); remove it to "
                         "start the search over") from None
