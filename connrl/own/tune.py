"""``connrl tune ENV``: a search over an agent's settings on seeds of its own (RL Zoo's ``--optimize``).

Each trial draws settings from the search space, trains one agent per tuning seed for ``steps`` steps and scores it by
the mean greedy return over ``eval_episodes`` episodes on evaluation seeds (``EVAL_SEED`` on); a trial's score is the
mean over its seeds. The tuning seeds (default 1000, 1001) are apart from the seeds connrl's own measurements report
(0-2, development 100-119, fresh 200-206), so a tuned setting is checked on seeds it never saw. Samplers: ``random``
(built in, seeded: trial k's settings are the same in every run) and ``tpe`` (Optuna's, the ``tune`` extra).

Files in ``out``: ``trials.csv`` (one row per finished trial, rewritten atomically after each: an interrupted search
resumes where it stopped), ``study.json`` (what was searched: a resumed search must search the same) and
``best.yml`` (the best trial as a settings file entry: ``connrl train ENV --hyperparams best.yml``).
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


def score(env_fn, kind: str, options: dict, seeds: list[int], steps: int, eval_episodes: int) -> list[float]:
    """Mean greedy return over ``eval_episodes`` evaluation episodes of one agent per seed, each trained ``steps``
    steps; a diverged agent scores -inf."""
    from connrl.own.api import evaluate, make_agent

    out = []
    for seed in seeds:
        agent = make_agent(env_fn(), kind, seed=seed, **options).learn(steps)
        if agent.divergence():
            out.append(-math.inf)
            continue
        out.append(float(np.mean(evaluate(agent, env_fn(), eval_episodes, seed=EVAL_SEED))))
    return out


def run_search(env_fn, study: dict, space: list[Dimension], out: Path, sampler: str = "random",
               progress=print) -> list[dict]:
    """Run (or resume) the search ``study`` describes; returns the finished trials, best first."""
    out.mkdir(parents=True, exist_ok=True)
    meta, trials_file = out / "study.json", out / "trials.csv"
    if meta.exists():
        try:
            old = read_json(meta, "study file", max_bytes=MAX_STUDY_BYTES)
        except FileError as exc:
            raise ValueError(f"{exc}; remove the folder {out} to start over") from None
        if not isinstance(old, dict) or {**old, "trials": None} != {**study, "trials": None}:  # more trials may
            raise ValueError(f"{out} holds another search ({meta} differs: env, agent, steps, seeds, space or "  # be
                             "sampler); choose another --out or remove that folder")  # asked of a search
    elif trials_file.exists():
        raise ValueError(f"{trials_file} has no study.json beside it, so what it searched is unknown; remove the "
                         f"folder {out} to start over")
    done = read_trials(trials_file, space) if trials_file.exists() else []
    optuna_study = _optuna_study(space, done, study["seed"]) if sampler == "tpe" else None  # Optuna missing:
    atomic_write_text(meta, json.dumps(study, indent=1) + "\n")  # refused before the study is written
    rng = np.random.default_rng(study["seed"])
    for k in range(study["trials"]):
        if optuna_study is None:
            params = {d.name: d.sample(rng) for d in space}  # drawn for every k: a resumed search draws the same
        if k < len(done):
            continue
        if optuna_study is not None:
            trial = optuna_study.ask()
            params = {d.name: _suggest(trial, d) for d in space}
        t0 = time.perf_counter()
        scores = score(env_fn, study["agent"], {**study["fixed"], **params}, study["seeds"], study["steps"],
                       study["eval_episodes"])
        mean = float(np.mean(scores))
        if optuna_study is not None:
            optuna_study.tell(trial, mean if math.isfinite(mean) else -1e300)
        done.append({"trial": k, "params": params, "scores": scores, "mean": mean,
                     "seconds": round(time.perf_counter() - t0, 2)})
        _write_trials(out / "trials.csv", done)
        progress(f"trial {k + 1}/{study['trials']}: {json.dumps(params)} -> mean greedy return {mean:.2f} "
                 f"({', '.join(f'{s:.1f}' for s in scores)})")
    return sorted(done, key=lambda t: -t["mean"])


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
