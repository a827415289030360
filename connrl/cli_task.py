"""The command line's own-task commands (``connrl train``, ``connrl evaluate``: connrl.api) and the argument
helpers every command shares."""

from __future__ import annotations

import argparse
from pathlib import Path


def _int_at_least(low: int):
    """An argparse type: a whole number >= low, with an error that says what is allowed."""

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if v < low:
            raise argparse.ArgumentTypeError(f"must be >= {low}, got {v}")
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


def cmd_train(args) -> int:
    import json

    import matplotlib.pyplot as plt

    from connrl.api import TAUGHT_KINDS, make_agent, options_from
    from connrl.core.lesson_files import load_lessons

    options = {}
    for item in args.option:
        key, sep, value = item.partition("=")
        if not sep:
            raise SystemExit(f"connrl: --option expects key=value, got {item!r}")
        try:
            options[key] = json.loads(value)
        except json.JSONDecodeError:
            options[key] = value
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
    _writable(out)
    returns = []
    try:
        agent = make_agent(env, args.agent, seed=args.seed, lessons=args.teach, **options)
        agent.learn(args.steps, callback=lambda a, r: returns.append((a.steps_done, r)), progress=not args.quiet)
    except ValueError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    agent.save(out)
    fig, ax = plt.subplots(figsize=(6, 3.5), dpi=110)
    ax.plot([s for s, _ in returns], [r for _, r in returns], lw=0.8)
    ax.set_xlabel("environment steps")
    ax.set_ylabel("return of each training trial")
    ax.set_title(f"{args.env_id}, {args.agent}, seed {args.seed}", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "curve.png")
    plt.close(fig)
    print(f"saved: {out} (agent.json, agent.npz, curve.png); `connrl evaluate {out}` tests it")
    return 0


def cmd_evaluate(args) -> int:
    import json

    import numpy as np

    from connrl.api import evaluate, load

    try:
        saved = json.loads((Path(args.path) / "agent.json").read_text())
        env_id = args.env or (saved.get("env_id") if isinstance(saved, dict) else None)
    except (OSError, ValueError):
        env_id = args.env
    if not env_id:
        raise SystemExit(f"connrl: {args.path} holds no readable agent with an environment id; give --env ENV_ID")
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
    s.add_argument("--steps", type=_positive_int, default=50_000, help="environment steps (default 50000)")
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
