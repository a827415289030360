"""The command line's own-task commands (``connrl train``, ``connrl evaluate``: connrl.api) and the argument
helpers every command shares."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
from pathlib import Path

MAX_STEPS = 10**10  # environment steps of one `connrl train`: months of compute at connrl's speed


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


def _writable(folder) -> None:
    """Refuse an output folder we cannot write in before any run starts (one line)."""
    from connrl.storage import check_writable_dir

    if not str(folder).strip():
        raise SystemExit("connrl: --out must name a folder, got an empty string")
    try:
        check_writable_dir(folder)
    except OSError as exc:
        raise SystemExit(f"connrl: cannot write to {folder}: {exc.strerror or exc}") from None


def _make_env(env_id: str):
    import gymnasium as gym

    import connrl  # noqa: F401  (registers the thesis's worlds)
    try:
        return gym.make(env_id)
    except Exception as exc:  # an unknown id, a module that is not installed, bad registration: one line
        raise SystemExit(f"connrl: cannot make environment {env_id!r}: {type(exc).__name__}: {exc}") from None


def _parse_options(items: list[str]) -> dict:
    import json

    options = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep:
            raise SystemExit(f"connrl: --option expects key=value, got {item!r}")
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


def cmd_train(args) -> int:
    from connrl.api import TAUGHT_KINDS, make_agent, options_from
    from connrl.core.lesson_files import load_lessons

    options = _parse_options(args.option)
    args.agent = args.agent or ("QCON-T" if args.teach else "QCON-R")
    try:
        options_from(options)  # every option and the lesson file checked before the environment is made
        if args.teach and args.agent not in TAUGHT_KINDS:
            raise ValueError(f"--teach gives lessons to {' or '.join(TAUGHT_KINDS)}, not to {args.agent}")
        if args.agent in TAUGHT_KINDS and not args.teach:
            raise ValueError(f"{args.agent} needs --teach FILE (a lesson file, connrl.record_lessons)")
        if args.teach:
            load_lessons(args.teach, env_id=args.env_id)
    except (ValueError, TypeError) as exc:
        raise SystemExit(f"connrl: {exc}") from None
    name = args.env_id.replace("/", "-").replace(":", "-")
    out = Path(args.save or f"runs/train/{name}-{args.agent}-seed{args.seed}")
    env = _make_env(args.env_id)
    fresh = not out.exists()
    _writable(out)
    returns: list[tuple[int, float]] = []
    saved: list[int] = []  # the steps of the latest good save

    def save(agent, deliver: bool = False) -> None:
        with _uninterrupted(deliver):
            agent.save(out)
            _write_curve(out, returns, args)
            saved.append(agent.steps_done)

    def checkpoint(agent, r) -> bool:
        returns.append((agent.steps_done, r))
        if agent.divergence():
            return False
        if args.checkpoint_every and agent.steps_done - (saved[-1] if saved else 0) >= args.checkpoint_every:
            try:
                save(agent, deliver=True)
            except OSError:  # a full disk: stop here; the last save below says what was not saved
                return False
        return True

    agent, stopped = None, None
    with _stop_signals():
        try:
            agent = make_agent(env, args.agent, seed=args.seed, lessons=args.teach, **options)
            agent.learn(args.steps, callback=checkpoint, progress=not args.quiet)
        except ValueError as exc:
            _remove_if_empty(out, fresh)
            raise SystemExit(f"connrl: {exc}") from None
        except (KeyboardInterrupt, _Terminated) as exc:
            stopped = exc
            if not args.quiet and agent is not None:
                print(flush=True)  # end the progress line
    return _finish(agent, out, fresh, stopped, saved, save)


def _remove_if_empty(out: Path, fresh: bool) -> None:
    if fresh and out.is_dir() and not any(out.iterdir()):
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
    print(f"saved: {out} (agent.json, agent.npz, curve.png); `connrl evaluate {out}` tests it")
    return 0


def _write_curve(out: Path, returns: list[tuple[int, float]], args) -> None:
    import io

    import matplotlib.pyplot as plt

    from connrl.storage import atomic_write_bytes

    fig, ax = plt.subplots(figsize=(6, 3.5), dpi=110)
    ax.plot([s for s, _ in returns], [r for _, r in returns], lw=0.8)
    ax.set_xlabel("environment steps")
    ax.set_ylabel("return of each training trial")
    ax.set_title(f"{args.env_id}, {args.agent}, seed {args.seed}", fontsize=9)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    atomic_write_bytes(out / "curve.png", buf.getvalue())


def _saved_env_id(path: str) -> str | None:
    """The registered environment id an agent folder names; FileError (one line) for a damaged agent file, and for
    an id that is not registered: ``gym.make`` would import the module of a ``module:Env`` id, so a file never
    chooses code to run (the user can, with --env)."""
    import gymnasium as gym

    import connrl  # noqa: F401  (registers the thesis's worlds)
    from connrl.api import KINDS
    from connrl.api_files import read_agent
    from connrl.storage import FileError

    m, _ = read_agent(Path(path), KINDS)
    env_id = m.get("env_id")
    if env_id is not None and (":" in env_id or env_id not in gym.registry):
        raise FileError(Path(path) / "agent.json", f"is {env_id!r}, not a registered Gymnasium environment (a "
                        "file never chooses code to import); give --env ENV_ID to choose the environment yourself",
                        "env_id")
    return env_id


def cmd_evaluate(args) -> int:
    import numpy as np

    from connrl.api import evaluate, load

    try:
        env_id = args.env or _saved_env_id(args.path)
    except ValueError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    if not env_id:
        raise SystemExit(f"connrl: {args.path} holds an agent without an environment id; give --env ENV_ID")
    env = _make_env(env_id)
    try:
        returns = evaluate(load(args.path, env), env, args.episodes, seed=args.seed)
    except ValueError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    print(f"{env_id}: greedy return over {len(returns)} episodes: mean {np.mean(returns):.2f}, min "
          f"{min(returns):.2f}, max {max(returns):.2f}")
    return 0


def add_own_task_commands(sub) -> None:
    """train, evaluate (connrl.api)."""
    s = sub.add_parser("train", help="train a thesis learner on any Gymnasium task", description="Train a thesis "
                       "learner on ENV_ID with inputs and values scaled from the task (connrl.api), then save it "
                       "(agent.json, agent.npz) and its learning curve (curve.png).")
    s.add_argument("env_id", help="a Gymnasium environment id, e.g. CartPole-v1 or connrl/PoleBalancing-v0")
    # connrl.api.KINDS, written out so that `connrl --help` does not import the agents (tests/test_api.py pins it)
    kinds = ("QCON", "QCON-R", "QCON-T", "AHCON", "AHCON-R", "AHCON-T", "window-Q", "recurrent-Q")
    s.add_argument("--agent", default=None, choices=kinds, metavar="AGENT",
                   help=f"one of {', '.join(kinds)} (default QCON-R, or QCON-T with --teach)")
    s.add_argument("--teach", default=None, metavar="FILE", help="a lesson file (connrl.record_lessons) that QCON-T "
                   "or AHCON-T replays after every trial")
    s.add_argument("--steps", type=_int_at_least(1, MAX_STEPS), default=50_000,
                   help="environment steps (default 50000)")
    s.add_argument("--checkpoint-every", type=_int_at_least(0, MAX_STEPS), default=10_000, metavar="STEPS",
                   help="save the agent every STEPS steps, so a crash loses at most that much (default 10000; 0: "
                   "only at the end). Ctrl-C or SIGTERM saves what was trained and stops")
    s.add_argument("--seed", type=_seed, default=0)
    s.add_argument("--save", default=None, help="folder to save in (default runs/train/ENV-AGENT-seedS)")
    s.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                   help="an AgentOptions field (connrl/api.py), e.g. --option gamma=0.95; repeat for several")
    s.add_argument("--quiet", action="store_true", help="no progress line")
    s.set_defaults(func=cmd_train)

    s = sub.add_parser("evaluate", help="the greedy return of a saved agent", description="Load an agent saved "
                       "by `connrl train` (or Agent.save) and print its greedy return over --episodes episodes.")
    s.add_argument("path", help="the agent's folder")
    s.add_argument("--episodes", type=_positive_int, default=10)
    s.add_argument("--seed", type=_seed, default=0, help="seed of the first episode (default 0)")
    s.add_argument("--env", default=None, help="environment id (default: the one it was trained on)")
    s.set_defaults(func=cmd_evaluate)
