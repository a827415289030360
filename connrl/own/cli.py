"""The command line's own-task commands (``connrl train``, ``connrl evaluate``: connrl.own.api) and the argument
helpers every command shares."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
from pathlib import Path

from connrl.own.settings import MAX_STEPS

DEFAULT_TRAIN_STEPS = 50_000


def _int_at_least(low: int, high: int | None = None):
    """An argparse type: a whole number >= low (and <= high), with an error that says what is allowed."""

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if v < low:
            raise argparse.ArgumentTypeError(f"must be >= {low}, got {v}")
        if high is not None and v > high:
            raise argparse.ArgumentTypeError(f"must be <= {high}, got {v}")
        return v

    return parse


_positive_int, _seed = _int_at_least(1), _int_at_least(0)


def _finite_float(text: str) -> float:
    import math

    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return v


def _writable(folder) -> None:
    """Refuse an output folder we cannot write in before any run starts (one line)."""
    from connrl.storage import check_writable_dir

    if not str(folder).strip():
        raise SystemExit("connrl: --out must name a folder, got an empty string")
    try:
        check_writable_dir(folder)
    except OSError as exc:
        raise SystemExit(f"connrl: cannot write to {folder}: {exc.strerror or exc}") from None


def _make_env(env_id: str, env_kwargs: dict | None = None):
    import gymnasium as gym

    import connrl  # noqa: F401  (registers the thesis's worlds)
    from connrl.own.spaces import check_render_dependency

    try:
        env = gym.make(env_id, **(env_kwargs or {}))
    except Exception as exc:  # an unknown id, a module that is not installed, bad registration: one line
        first = (str(exc).strip().splitlines() or [""])[0]
        raise SystemExit(f"connrl: cannot make environment {env_id!r}: {type(exc).__name__}: {first}") from None
    try:
        check_render_dependency(env, env_id, env_kwargs or {})
    except ValueError as exc:
        env.close()
        raise SystemExit(f"connrl: {exc}") from None
    return env


def key_value(text: str) -> str:
    """An argparse type: KEY=VALUE (one per flag: a bare word after the flag is the command's, not the flag's)."""
    key, sep, _ = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r} (one KEY=VALUE per flag; an environment id "
                                         "goes before the options)")
    return text


def folder_name(text: str) -> str:
    """An argparse type: a folder path, not empty (an empty one would silently mean the default)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("must name a folder, got an empty string")
    return text


def _parse_options(items: list[str], flag: str = "--option") -> dict:
    """KEY=VALUE items as a dict, each value read as JSON where it is (numbers, true, null, lists) else a string."""
    import json

    options = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise SystemExit(f"connrl: {flag} expects KEY=VALUE, got {item!r}")
        try:
            options[key] = json.loads(value)
        except json.JSONDecodeError:
            options[key] = value
    return options


class _Terminated(BaseException):
    """SIGTERM, raised where the training loop is, so it stops and saves as it does on Ctrl-C."""


@contextlib.contextmanager
def _stop_signals():
    """SIGINT and SIGTERM interrupt the block (KeyboardInterrupt / _Terminated) and are ignored while an agent is
    written, so a save is never cut in half."""
    def terminate(signum, frame):
        raise _Terminated

    old = signal.signal(signal.SIGTERM, terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


@contextlib.contextmanager
def _uninterrupted(deliver: bool):
    """SIGINT / SIGTERM wait until the block (a save) is done; with ``deliver`` one that came meanwhile then stops
    the training as it would have (a signal that met a checkpoint is not lost)."""
    pending: list[int] = []
    old = (signal.signal(signal.SIGINT, lambda signum, frame: pending.append(signum)),
           signal.signal(signal.SIGTERM, lambda signum, frame: pending.append(signum)))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old[0])
        signal.signal(signal.SIGTERM, old[1])
    if deliver and pending:
        raise KeyboardInterrupt if pending[0] == signal.SIGINT else _Terminated


def _train_settings(args) -> dict:
    """What `connrl train` will do: the agent, steps, options and env kwargs from the settings file (shipped or
    --hyperparams) overridden by the command line, all checked before anything is made."""
    from connrl.core.lesson_files import load_lessons
    from connrl.own.api import TAUGHT_KINDS, options_from
    from connrl.own.settings import task_settings

    args.agent = args.agent or ("QCON-T" if args.teach else "QCON-R")
    try:
        entry, source = task_settings(args.env_id, args.agent, args.hyperparams)
        entry = entry or {"n_timesteps": None, "env_kwargs": {}, "options": {}}
        options = {**entry["options"], **_parse_options(args.option)}
        env_kwargs = {**entry["env_kwargs"], **_parse_options(args.env_kwargs, "--env-kwargs")}
        options_from(options)  # every option and the lesson file checked before the environment is made
        if args.teach and args.agent not in TAUGHT_KINDS:
            raise ValueError(f"--teach gives lessons to {' or '.join(TAUGHT_KINDS)}, not to {args.agent}")
        if args.agent in TAUGHT_KINDS and not args.teach:
            raise ValueError(f"{args.agent} needs --teach FILE (a lesson file, connrl.record_lessons)")
        if args.teach:
            load_lessons(args.teach, env_id=args.env_id)
        steps = args.steps or entry["n_timesteps"] or DEFAULT_TRAIN_STEPS
        if args.stop_at is not None and args.eval_every == 0:
            raise ValueError("--stop-at stops when an evaluation reaches it: give --eval-every STEPS too")
        if args.tensorboard:
            import importlib.util

            if importlib.util.find_spec("tensorboardX") is None:
                raise ValueError("--tensorboard needs tensorboardX: pip install 'connrl[tensorboard]'")
    except (ValueError, TypeError) as exc:
        raise SystemExit(f"connrl: {exc}") from None
    return {"env_id": args.env_id, "env_kwargs": env_kwargs, "agent": args.agent, "seed": args.seed,
            "steps": steps, "options": options, "teach": args.teach, "settings_from": source}


AUTO_EVALS, MIN_AUTO_EVAL = 20, 1000  # the default evaluations of a run, and the fewest steps between two


def auto_eval_every(env, stop_at: float | None, steps: int) -> int:
    """`connrl train`'s default --eval-every: where success is defined (the env's registered reward threshold, e.g.
    CartPole-v1's 475, or --stop-at), ``AUTO_EVALS`` evaluations over the run, at least ``MIN_AUTO_EVAL`` steps
    apart; else 0 (none)."""
    threshold = getattr(getattr(env, "spec", None), "reward_threshold", None)
    return max(MIN_AUTO_EVAL, steps // AUTO_EVALS) if stop_at is not None or threshold is not None else 0


def _read_run_settings(file: Path) -> dict:
    """A `connrl train` run's settings.json (read by connrl.storage.read_json: strict, size-capped); ValueError in one
    line naming the file otherwise."""
    from connrl.storage import check_number, read_json

    s = read_json(file, "connrl train settings file")
    if not isinstance(s, dict):
        raise ValueError(f"{file}: is not a connrl train settings file")
    if "steps" in s:  # the resumed run's budget: under the same cap as --steps
        check_number(file, "steps", s["steps"], 1, MAX_STEPS, integer=True)
    return s


def _resumed_settings(out: Path, settings: dict, args) -> dict:
    """The settings of the run in ``out`` that --resume continues; the command may change only --steps."""
    file = out / "settings.json"
    if not (out / "agent.json").exists():
        raise SystemExit(f"connrl: --resume: {out} holds no trained agent (agent.json) to continue")
    try:
        old = _read_run_settings(file)
    except ValueError as exc:
        raise SystemExit(f"connrl: --resume: {exc}") from None
    for key in ("env_id", "agent", "seed", "env_kwargs", "options", "teach"):
        if old.get(key) != settings[key]:
            raise SystemExit(f"connrl: --resume: {key} is {settings[key]!r} here but {old.get(key)!r} in {file}; a "
                             "resumed run keeps its settings (only --steps may change)")
    return {**old, "steps": args.steps or old.get("steps") or settings["steps"]}  # no --steps: the run's own


@contextlib.contextmanager
def one_writer(out: Path, option: str):
    """The folder's lock (``connrl.storage.run_lock``, as `connrl run` takes it) for the block; a second writer is
    refused in one line before any work."""
    from connrl.storage import run_lock

    with contextlib.ExitStack() as stack:
        try:  # only taking the lock is refused here; the block's own errors pass through
            stack.enter_context(run_lock(out, option))
        except BlockingIOError as exc:
            raise SystemExit(f"connrl: {exc.strerror}") from None
        yield


def cmd_train(args) -> int:
    out, settings = _train_folder(args, _train_settings(args))
    env = _make_env(args.env_id, settings["env_kwargs"])
    if args.eval_every is None:  # where success is defined, evaluate and keep the best agent by default
        args.eval_every = auto_eval_every(env, args.stop_at, settings["steps"])
    eval_env = _make_env(args.env_id, settings["env_kwargs"]) if args.eval_every else None
    fresh = not out.exists()
    _writable(out)
    with one_writer(out, "--save"):
        if args.resume or not (out / "agent.json").exists():  # another writer may have saved since the first check
            return _train(args, out, settings, env, eval_env, fresh)
        raise SystemExit(f"connrl: {out} holds a trained agent already: --resume continues it, --save DIR trains a "
                         "new one elsewhere")


def _train(args, out: Path, settings: dict, env, eval_env, fresh: bool) -> int:
    import json

    from connrl.own.api import load, make_agent
    from connrl.own.callbacks import EvalCallback, ProgressLog, TensorBoardLog, keep_numbered
    from connrl.own.plots import write_training_curve
    from connrl.storage import atomic_write_text

    saved: list[int] = []  # the steps of the latest good save
    evaluation = None if eval_env is None else EvalCallback(
        eval_env, args.eval_every, args.eval_episodes, best_path=out / "best", stop_at=args.stop_at,
        verbose=not args.quiet)
    try:
        log = ProgressLog(out / "progress.csv", evaluation, resume=args.resume)
    except ValueError as exc:
        raise SystemExit(f"connrl: --resume: {exc}") from None
    if evaluation is not None:  # a resumed run's best/ stays until an evaluation beats it
        evaluation.best_mean = max((r["eval_mean"] for r in log.rows if r["eval_mean"] is not None),
                                   default=evaluation.best_mean)

    def save(agent, deliver: bool = False) -> None:
        with _uninterrupted(deliver):
            agent.save(out)
            keep_numbered(agent, out, args.keep)
            atomic_write_text(out / "settings.json", json.dumps(settings, indent=1) + "\n")  # --resume reads it
            log.flush()
            write_training_curve(out, log.rows, f"{args.env_id}, {settings['agent']}, seed {settings['seed']}")
            saved.append(agent.steps_done)

    agent, stopped = None, None
    with _stop_signals():
        try:
            if args.resume:
                agent = load(out, env)
                saved.append(agent.steps_done)
            else:
                agent = make_agent(env, settings["agent"], seed=settings["seed"], lessons=settings["teach"],
                                   **settings["options"])
            left = settings["steps"] - agent.steps_done
            if left <= 0:
                print(f"connrl: {out} is trained for {agent.steps_done} steps already (--steps {settings['steps']})")
                return 0
            board = TensorBoardLog(args.tensorboard, evaluation) if args.tensorboard else None
            callbacks = [c for c in (evaluation, log, board, _checkpoints(args.checkpoint_every, saved, save)) if c]
            agent.learn(left, callback=callbacks, progress=not args.quiet)
        except ValueError as exc:
            _remove_if_empty(out, fresh)
            raise SystemExit(f"connrl: {exc}") from None
        except (KeyboardInterrupt, _Terminated) as exc:
            stopped = exc
            if not args.quiet and agent is not None:
                print(flush=True)  # end the progress line
    code = _finish(agent, out, fresh, stopped, saved, save)
    return _after_evaluation(evaluation, log.rows, args.stop_at, out, agent, code)


def _after_evaluation(evaluation, rows: list[dict], stop_at: float | None, out: Path, agent, code: int) -> int:
    """What the run's evaluations say once it is saved: where the best agent is, or (one line) that it could not be
    kept. A run whose own save failed has said so already."""
    if evaluation is None or code != 0:
        return code
    if evaluation.save_error is not None:
        e = evaluation.save_error
        print(f"connrl: training stopped at step {agent.steps_done}: the best agent could not be kept in {out / 'best'}"
              f" ({e.strerror or e})", file=sys.stderr)
        return 1
    if evaluation.results:
        _say_best(rows, evaluation, stop_at, out)
    return 0


def _say_best(rows: list[dict], evaluation, stop_at: float | None, out: Path) -> None:
    # a resumed run's evaluations from before the resume count too: best/ may be from then
    best = max((r for r in rows if r["eval_mean"] is not None), key=lambda r: r["eval_mean"])  # the first of
    reached = " (--stop-at reached)" if stop_at is not None and evaluation.results[-1][1] >= stop_at else ""  # equals
    print(f"best evaluation: mean return {best['eval_mean']:.2f} at step {best['steps']}, kept in {out / 'best'}"
          f"{reached}")


def _train_folder(args, settings: dict) -> tuple[Path, dict]:
    """The folder `connrl train` saves in and the settings it trains with: a new run's, or with --resume the
    saved run's; a folder holding an agent is never overwritten by a new run."""
    name = args.env_id.replace("/", "-").replace(":", "-")
    out = Path(args.save or f"runs/train/{name}-{args.agent}-seed{args.seed}")
    if args.resume:
        return out, _resumed_settings(out, settings, args)
    if (out / "agent.json").exists():
        raise SystemExit(f"connrl: {out} holds a trained agent already: --resume continues it, --save DIR trains "
                         "a new one elsewhere")
    if settings["settings_from"] and not args.quiet:
        print(f"settings: {settings['settings_from']}")
    return out, settings


def _checkpoints(every: int, saved: list[int], save):
    """`connrl train`'s own keeper: a diverged agent stops training; every ``every`` steps the agent, the log and
    the curve are saved as one (a signal waits for the save, then stops as it would have)."""
    from connrl.own.callbacks import Callback

    class Checkpoints(Callback):
        def on_trial_end(self, agent, stats):
            if agent.divergence():
                return False
            if every and agent.steps_done - (saved[-1] if saved else 0) >= every:
                try:
                    save(agent, deliver=True)
                except OSError:  # a full disk: stop here; the last save says what was not saved
                    return False
            return True

    return Checkpoints()


def _remove_if_empty(out: Path, fresh: bool) -> None:
    """A folder this command made and left with nothing but its lock file is removed (the lock file with it)."""
    if fresh and out.is_dir() and {p.name for p in out.iterdir()} <= {".connrl-run.lock"}:
        with contextlib.suppress(OSError):
            (out / ".connrl-run.lock").unlink()
            out.rmdir()


def _finish(agent, out: Path, fresh: bool, stopped, saved: list[int], save) -> int:
    """Save what training reached and say so in one line: stopped by a signal (130 / 143), diverged (1), a write
    that failed (1), or done (0)."""
    code = 0 if stopped is None else 130 if isinstance(stopped, KeyboardInterrupt) else 143
    how = "" if stopped is None else "interrupted (Ctrl-C); " if code == 130 else "stopped (SIGTERM); "
    if agent is None or agent.steps_done == 0:  # stopped in the warm-up: nothing was trained
        _remove_if_empty(out, fresh)
        print(f"connrl: {how}nothing was trained yet, so nothing was saved", file=sys.stderr)
        return code
    problem = agent.divergence()
    if problem:
        kept = f"; the last good checkpoint (step {saved[-1]}) is kept in {out}" if saved else ""
        _remove_if_empty(out, fresh)
        print(f"connrl: {how}training diverged by step {agent.steps_done} ({problem}): it was not saved{kept}; a "
              "smaller learning rate (--option lr=...) keeps the weights bounded", file=sys.stderr)
        return code or 1
    try:
        save(agent)
    except OSError as exc:
        kept = f" (the checkpoint of step {saved[-1]} is kept there)" if saved else ""
        _remove_if_empty(out, fresh)
        print(f"connrl: {how}the agent trained for {agent.steps_done} steps was NOT saved: cannot write {out}: "
              f"{exc.strerror or exc}{kept}", file=sys.stderr)
        return code or 1
    if stopped is not None:
        print(f"connrl: {how}saved the agent trained for {agent.steps_done} steps in {out}; `connrl evaluate "
              f"{out}` tests it", file=sys.stderr)
        return code
    print(f"saved: {out} (agent.json, agent.npz, progress.csv, curve.png); `connrl evaluate {out}` tests it")
    return 0


def add_own_task_commands(sub) -> None:
    """train (connrl.own.api); ``connrl.own.cli_evaluate.add_evaluate_command`` adds evaluate."""
    s = sub.add_parser("train", help="train a thesis learner on any Gymnasium task", description="Train a thesis "
                       "learner on ENV_ID with inputs and values scaled from the task (connrl.own.api), then save it "
                       "(agent.json, agent.npz) and its learning curve (curve.png).")
    s.add_argument("env_id", help="a Gymnasium environment id, e.g. CartPole-v1 or connrl/PoleBalancing-v0")
    # connrl.own.api.KINDS, written out so that `connrl --help` does not import the agents (tests/test_api.py pins it)
    kinds = ("QCON", "QCON-R", "QCON-T", "AHCON", "AHCON-R", "AHCON-T", "window-Q", "recurrent-Q")
    s.add_argument("--agent", default=None, choices=kinds, metavar="AGENT",
                   help=f"one of {', '.join(kinds)} (default QCON-R, or QCON-T with --teach)")
    s.add_argument("--teach", default=None, metavar="FILE", help="a lesson file (connrl.record_lessons) that QCON-T "
                   "or AHCON-T replays after every trial")
    s.add_argument("--steps", type=_int_at_least(1, MAX_STEPS), default=None,
                   help="environment steps in all (default: the settings file's n_timesteps, else 50000)")
    s.add_argument("--checkpoint-every", type=_int_at_least(0, MAX_STEPS), default=10_000, metavar="STEPS",
                   help="save the agent, progress.csv and curve.png every STEPS steps, so a crash loses at most that "
                   "much (default 10000; 0: only at the end). Ctrl-C or SIGTERM saves what was trained and stops")
    s.add_argument("--keep", type=_int_at_least(0, 1000), default=0, metavar="N", help="also keep the last N "
                   "checkpoints, numbered, in SAVE/checkpoints/step-STEPS (default 0: only the latest, in SAVE)")
    s.add_argument("--resume", action="store_true", help="continue the agent saved in the --save folder (its "
                   "latest checkpoint) up to --steps in all, with its settings")
    s.add_argument("--eval-every", type=_int_at_least(0, MAX_STEPS), default=None, metavar="STEPS",
                   help="greedy evaluation on a separate env every STEPS steps (at the next trial end); the best "
                   "agent is kept in SAVE/best. Default: where the env defines a reward threshold (CartPole-v1: "
                   "475) or --stop-at is given, 20 evaluations a run (at least 1000 steps apart); else 0 (none)")
    s.add_argument("--eval-episodes", type=_positive_int, default=5, metavar="N", help="episodes per evaluation")
    s.add_argument("--stop-at", type=_finite_float, default=None, metavar="RETURN",
                   help="stop once an evaluation's mean return reaches RETURN (needs --eval-every)")
    s.add_argument("--tensorboard", default=None, metavar="DIR", help="also write TensorBoard scalars to DIR "
                   "(pip install 'connrl[tensorboard]')")
    s.add_argument("--hyperparams", default=None, metavar="FILE", help="a settings file (RL Zoo's shape, "
                   "connrl/own/settings.py); default: the shipped one for the agent, if it has ENV_ID")
    s.add_argument("--env-kwargs", action="append", type=key_value, default=[], metavar="KEY=VALUE",
                   help="an argument of gymnasium.make(ENV_ID, ...), e.g. --env-kwargs is_slippery=false; repeat "
                   "for several")
    s.add_argument("--seed", type=_seed, default=0)
    s.add_argument("--save", type=folder_name, default=None,
                   help="folder to save in (default runs/train/ENV-AGENT-seedS)")
    s.add_argument("--option", action="append", type=key_value, default=[], metavar="KEY=VALUE",
                   help="an AgentOptions field (connrl/own/api.py), e.g. --option gamma=0.95; repeat for several")
    s.add_argument("--quiet", action="store_true", help="no progress line")
    s.set_defaults(func=cmd_train)

