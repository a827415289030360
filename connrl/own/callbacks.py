"""Watching and keeping an agent while it learns, in Stable-Baselines3's shape (``agent.learn(n, callback=...)``).

    from connrl.own.callbacks import CheckpointCallback, EvalCallback, ProgressLog
    eval_cb = EvalCallback(gym.make("CartPole-v1"), every=5_000, episodes=5, best_path="runs/cp/best", stop_at=475)
    agent.learn(50_000, callback=[ProgressLog("runs/cp/progress.csv"), eval_cb, CheckpointCallback(10_000, "runs/cp")])

The hooks (``Callback``, ``CallbackList``) are ``connrl.core.training``'s, the one loop every thesis run trains
with too. connrl's learners change their nets at the end of a trial (replay, 3.5), so every callback runs after a trial:
``every=N`` means at the first trial end at or past each multiple of N steps (SB3 checks after any step). A callback
returning False from ``on_trial_end`` stops training. A plain function ``f(agent, trial_return)`` still works.
Evaluation is greedy (T = 0) on its own environment and seeds (``eval_seed`` on), so it never moves the learner's
random stream: a run with and without evaluation learns the same.
"""

from __future__ import annotations

import csv
import io
import json
import math
import shutil
import time
from pathlib import Path

import numpy as np

from connrl.core.training import Callback, CallbackList, as_callback  # noqa: F401 (the hooks' home)
from connrl.storage import atomic_write_text

# progress.csv's columns: one row per training trial; the eval_* cells are filled on trials that ended an evaluation
LOG_COLUMNS = ("steps", "trial", "return", "length", "temperature", "seconds", "eval_mean", "eval_std", "eval_min")


def _trial_temperature(agent) -> float:
    """The temperature (Q units) the trial just ended was played at: set when it began (or when its first reward set
    the value scale), not the one the next trial will use."""
    return float(agent.learner.explore.base)


def _check_every(name: str, every) -> int:
    if isinstance(every, bool) or not isinstance(every, int) or every < 1:
        raise ValueError(f"{name} must be a whole number of steps >= 1, got {every!r}")
    return every


class _Every:
    """True at the first call at or past each multiple of ``every`` steps (counted from the agent's step 0, so a
    resumed run keeps the schedule)."""

    def __init__(self, every: int):
        self.every, self.done = every, 0

    def start(self, steps: int) -> None:
        """At the start of training: due next at the first multiple past ``steps``."""
        self.done = steps // self.every

    def due(self, steps: int) -> bool:
        k = steps // self.every
        if k > self.done:
            self.done = k
            return True
        return False


class EvalCallback(Callback):
    """Greedy evaluation every ``every`` steps on ``eval_env`` (``episodes`` episodes, seeds ``eval_seed`` on;
    keep them apart from the seeds you report); keeps the best agent in ``best_path`` (when given) and stops
    training once the mean return reaches ``stop_at`` (when given). ``results`` holds (steps, mean, std, min); the
    agent's ``evaluation`` the latest, saved with it (so ``connrl.load`` of the best says what it scored). A best
    agent that cannot be written (a full disk) stops training, the error kept in ``save_error``."""

    def __init__(self, eval_env, every: int = 10_000, episodes: int = 5, eval_seed: int = 1_000_000,
                 best_path=None, stop_at: float | None = None, max_episode_steps: int | None = None,
                 verbose: bool = False):
        self.every = _Every(_check_every("every", every))
        if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
            raise ValueError(f"episodes must be a whole number >= 1, got {episodes!r}")
        if stop_at is not None and not (isinstance(stop_at, (int, float)) and math.isfinite(stop_at)):
            raise ValueError(f"stop_at must be a finite number or None, got {stop_at!r}")
        self.env, self.episodes, self.eval_seed = eval_env, episodes, int(eval_seed)
        self.best_path = Path(best_path) if best_path is not None else None
        self.stop_at, self.max_episode_steps, self.verbose = stop_at, max_episode_steps, verbose
        self.results: list[tuple[int, float, float, float]] = []
        self.best_mean = -math.inf
        self.last: tuple[int, float, float, float] | None = None  # the latest evaluation
        self.save_error: OSError | None = None  # why the best agent could not be kept, if it could not

    def on_training_start(self, agent, total_steps):
        agent.check_env(self.env)
        self.every.start(agent.steps_done)

    def on_trial_end(self, agent, stats):
        if not self.every.due(agent.steps_done):
            return True
        return self.evaluate(agent)

    def of_trial(self, agent) -> tuple[int, float, float, float] | None:
        """The evaluation run at the end of the agent's latest trial, or None (for logs that run after this)."""
        return self.last if self.last is not None and self.last[0] == agent.steps_done else None

    def evaluate(self, agent) -> bool:
        """Evaluate now; False when ``stop_at`` is reached."""
        returns = np.asarray(agent.evaluate(self.env, self.episodes, seed=self.eval_seed,
                                            max_episode_steps=self.max_episode_steps))
        self.last = (agent.steps_done, float(returns.mean()), float(returns.std()), float(returns.min()))
        self.results.append(self.last)
        new_best = self.last[1] > self.best_mean
        agent.evaluation = {"steps": self.last[0], "mean": self.last[1], "std": self.last[2], "min": self.last[3],
                            "episodes": self.episodes, "eval_seed": self.eval_seed, "best": new_best}
        if new_best:
            self.best_mean = self.last[1]
            if self.best_path is not None and not agent.divergence():
                try:
                    agent.save(self.best_path)
                except OSError as exc:  # a full disk: training stops, and save_error says why
                    self.save_error = exc
                    return False
        if self.verbose:
            print(f"\neval at step {agent.steps_done}: mean return {self.last[1]:.2f} +- {self.last[2]:.2f}"
                  + (" (new best)" if new_best else ""), flush=True)
        return not (self.stop_at is not None and self.last[1] >= self.stop_at)


class CheckpointCallback(Callback):
    """Save the agent in ``path`` every ``every`` steps (one folder, replaced atomically: the latest checkpoint
    survives a crash in the middle of the next; ``connrl.load(path)`` resumes it); with ``keep`` N > 0 the last N
    checkpoints are kept too, numbered (``keep_numbered``). A diverged agent is not saved, and stops training."""

    def __init__(self, every: int, path, keep: int = 0):
        self.every, self.path = _Every(_check_every("every", every)), Path(path)
        if isinstance(keep, bool) or not isinstance(keep, int) or keep < 0:
            raise ValueError(f"keep must be a whole number of checkpoints >= 0, got {keep!r}")
        self.keep = keep

    def on_training_start(self, agent, total_steps):
        self.every.start(agent.steps_done)

    def on_trial_end(self, agent, stats):
        if not self.every.due(agent.steps_done):
            return True
        if agent.divergence():
            return False
        agent.save(self.path)
        keep_numbered(agent, self.path, self.keep)
        return True


def keep_numbered(agent, path, keep: int) -> None:
    """Save ``agent`` also as ``path/checkpoints/step-<steps>`` and remove all but the ``keep`` latest such copies
    (SB3's numbered checkpoints); nothing with ``keep`` 0."""
    if not keep:
        return
    folder = Path(path) / "checkpoints"
    agent.save(folder / f"step-{agent.steps_done:011d}")  # 11 digits: any step count up to MAX_STEPS sorts
    for old in sorted(folder.glob("step-*"))[:-keep]:
        shutil.rmtree(old, ignore_errors=True)


class ProgressLog(Callback):
    """progress.csv (``LOG_COLUMNS``): one row per training trial, the evaluation of ``eval_callback`` (when given)
    on the trial that ran it; beside it ``monitor.csv``, the same trials in SB3's Monitor format (a JSON header line,
    then ``r,l,t``: return, length, seconds since the start), which RL Zoo's plotting scripts and SB3's
    ``load_results`` read. Rewritten atomically every ``flush_every`` seconds and at the end, so a crash loses at most
    that much; a resumed run (``resume=True``) keeps the rows up to the agent's step count and appends."""

    def __init__(self, path, eval_callback: EvalCallback | None = None, resume: bool = False,
                 flush_every: float = 10.0):
        self.path, self.eval = Path(path), eval_callback
        self.rows: list[dict] = read_progress(self.path) if resume and self.path.exists() else []
        self.flush_every, self._flushed, self._t0 = flush_every, 0.0, 0.0
        self.monitor_path = self.path.with_name("monitor.csv")
        self._header = {"t_start": round(time.time(), 3), "env_id": ""}

    def on_training_start(self, agent, total):
        self.rows = [r for r in self.rows if r["steps"] <= agent.steps_done]  # rows past the checkpoint are redone
        before = self.rows[-1]["seconds"] if self.rows else 0.0
        self._t0 = time.perf_counter() - before
        self._header = {"t_start": round(time.time() - before, 3), "env_id": agent.env_id or ""}
        self._flushed = time.perf_counter()

    def on_trial_end(self, agent, stats):
        ev = self.eval.of_trial(agent) if self.eval is not None else None
        self.rows.append({"steps": agent.steps_done, "trial": agent.trials_done, "return": float(stats.total_reward),
                          "length": stats.steps, "temperature": _trial_temperature(agent),
                          "seconds": round(time.perf_counter() - self._t0, 3),
                          "eval_mean": ev[1] if ev else None, "eval_std": ev[2] if ev else None,
                          "eval_min": ev[3] if ev else None})
        if time.perf_counter() - self._flushed >= self.flush_every:
            self._try_flush()
        return True

    def on_training_end(self, agent):
        self._try_flush()

    def _try_flush(self) -> None:
        try:
            self.flush()
        except OSError:  # a full disk must not end training: the next save of the agent reports it
            pass

    def flush(self) -> None:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(LOG_COLUMNS)
        for r in self.rows:
            w.writerow(["" if r[c] is None else f"{r[c]:.6g}" if isinstance(r[c], float) else r[c]
                        for c in LOG_COLUMNS])
        atomic_write_text(self.path, buf.getvalue())
        monitor = [f"#{json.dumps(self._header)}", "r,l,t"]
        monitor += [f"{round(r['return'], 6)},{r['length']},{r['seconds']}" for r in self.rows]
        atomic_write_text(self.monitor_path, "\n".join(monitor) + "\n")
        self._flushed = time.perf_counter()


class TensorBoardLog(Callback):
    """TensorBoard scalars (the ``tensorboard`` extra: tensorboardX) in ``logdir``, SB3's names: rollout/ep_rew,
    rollout/ep_len, train/temperature per trial and eval/mean_reward per evaluation of ``eval_callback``, against
    environment steps. ``tensorboard --logdir DIR`` shows them."""

    def __init__(self, logdir, eval_callback: EvalCallback | None = None):
        try:
            from tensorboardX import SummaryWriter
        except ImportError:
            raise ValueError("TensorBoard logs need tensorboardX: pip install 'connrl[tensorboard]'") from None
        try:
            self.writer = SummaryWriter(str(logdir))
        except OSError as exc:
            raise ValueError(f"cannot write TensorBoard logs in {logdir}: {exc.strerror or exc}") from None
        self.eval = eval_callback

    def on_trial_end(self, agent, stats):
        s, w = agent.steps_done, self.writer
        w.add_scalar("rollout/ep_rew", float(stats.total_reward), s)
        w.add_scalar("rollout/ep_len", stats.steps, s)
        w.add_scalar("train/temperature", _trial_temperature(agent), s)
        ev = self.eval.of_trial(agent) if self.eval is not None else None
        if ev is not None:
            w.add_scalar("eval/mean_reward", ev[1], s)
        return True

    def on_training_end(self, agent):
        self.writer.flush()
        self.writer.close()


MAX_PROGRESS_BYTES = 32 << 20  # a row per trial, ~100 bytes: far beyond any run, and cheap to parse
MAX_LOGGED = 1e15  # steps, returns, ... a run writes


def read_progress(path) -> list[dict]:
    """The rows of a progress.csv (numbers; None for empty cells); ValueError in one line naming the file when it
    is not one."""
    path = Path(path)
    from connrl.storage import FileError, read_limited

    try:
        lines = list(csv.reader(io.StringIO(read_limited(path, MAX_PROGRESS_BYTES, "progress.csv").decode())))
    except FileError as exc:
        raise ValueError(str(exc)) from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise ValueError(f"{path}: is not a connrl progress.csv ({exc})") from None
    if not lines or tuple(lines[0]) != LOG_COLUMNS:
        raise ValueError(f"{path}: is not a connrl progress.csv (its header must be {','.join(LOG_COLUMNS)})")
    rows = []
    for n, cells in enumerate(lines[1:], start=2):
        if len(cells) != len(LOG_COLUMNS):
            raise ValueError(f"{path}: line {n} has {len(cells)} cells, not {len(LOG_COLUMNS)}")
        try:
            row = {c: (None if v == "" else int(v) if c in ("steps", "trial", "length") else float(v))
                   for c, v in zip(LOG_COLUMNS, cells, strict=True)}
        except ValueError:
            raise ValueError(f"{path}: line {n} holds a cell that is not a number") from None
        if not all(v is None or abs(v) <= MAX_LOGGED for v in row.values()):  # inf, nan, or a forged huge value
            raise ValueError(f"{path}: line {n} holds a cell that is not a finite number within ±{MAX_LOGGED:.0e}")
        rows.append(row)
    return rows
