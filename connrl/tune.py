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

from connrl.storage import atomic_write_text

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

    def describe(self) -> str:
        if self.choices is not None:
            return ",".join(json.dumps(c) for c in self.choices)
        return f"{self.low}:{self.high}" + (":log" if self.log else "")


def parse_dimension(text: str) -> Dimension:
    """``name=a,b,c`` (choices, JSON values), ``name=low:high`` or ``name=low:high:log``; ValueError in one line."""
    from connrl.api import AgentOptions

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
    from connrl.api import options_from

    for d in space:
        for v in d.choices if d.choices is not None else (d.low, d.high):
            try:
                options_from({**fixed, d.name: v})
            except (ValueError, TypeError) as exc:
                raise ValueError(f"--space {d.name}: {exc}") from None


def score(env_fn, kind: str, options: dict, seeds: list[int], steps: int, eval_episodes: int) -> list[float]:
    """Mean greedy return over ``eval_episodes`` evaluation episodes of one agent per seed, each trained ``steps``
    steps; a diverged agent scores -inf."""
    from connrl.api import evaluate, make_agent

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
            old = json.loads(meta.read_text())
        except (OSError, ValueError) as exc:
            raise ValueError(f"{meta}: cannot be read as a study ({exc}); remove the folder {out} to start over") \
                from None
        if not isinstance(old, dict) or {**old, "trials": None} != {**study, "trials": None}:  # more trials may
            raise ValueError(f"{out} holds another search ({meta} differs: env, agent, steps, seeds, space or "  # be
                             "sampler); choose another --out or remove that folder")  # asked of a search
    elif trials_file.exists():
        raise ValueError(f"{trials_file} has no study.json beside it, so what it searched is unknown; remove the "
                         f"folder {out} to start over")
    done = read_trials(trials_file) if trials_file.exists() else []
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


def _write_trials(path: Path, trials: list[dict]) -> None:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(TRIAL_COLUMNS)
    for t in trials:
        w.writerow([t["trial"], json.dumps(t["params"]), json.dumps([s if math.isfinite(s) else None
                                                                     for s in t["scores"]]),
                    f"{t['mean']:.6g}", t["seconds"]])
    atomic_write_text(path, buf.getvalue())


def read_trials(path: Path) -> list[dict]:
    """The finished trials of a trials.csv; ValueError in one line when it is damaged."""
    try:
        rows = list(csv.reader(io.StringIO(path.read_text())))
        if not rows or tuple(rows[0]) != TRIAL_COLUMNS:
            raise ValueError("its header is not " + ",".join(TRIAL_COLUMNS))
        trials = []
        for k, r in enumerate(rows[1:]):
            scores = [-math.inf if s is None else float(s) for s in json.loads(r[2])]
            trials.append({"trial": int(r[0]), "params": json.loads(r[1]), "scores": scores, "mean": float(r[3]),
                           "seconds": float(r[4])})
            if trials[-1]["trial"] != k or not isinstance(trials[-1]["params"], dict):
                raise ValueError(f"row {k + 2} is not trial {k}")
            if math.isnan(trials[-1]["mean"]):
                raise ValueError(f"row {k + 2} has no mean score")
        return trials
    except (OSError, ValueError, IndexError, TypeError, csv.Error) as exc:  # UnicodeDecodeError is a ValueError
        raise ValueError(f"{path}: is not a connrl trials file ({exc}); remove it to start the search over") from None
