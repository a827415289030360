"""``connrl evaluate PATH``: the command line that loads a saved agent and plays it greedily, saying which agent it
loaded and what its run's evaluation said of it."""

from __future__ import annotations

from pathlib import Path

from connrl.own.cli import _make_env, _parse_options, _positive_int, _read_run_settings, _seed, key_value


def _saved_env_id(path: str) -> str | None:
    """The registered environment id an agent folder names; FileError (one line) for a damaged agent file, and for
    an id that is not registered: ``gym.make`` would import the module of a ``module:Env`` id, so a file never
    chooses code to run (the user can, with --env)."""
    import gymnasium as gym

    import connrl  # noqa: F401  (registers the thesis's worlds)
    from connrl.own.api import KINDS
    from connrl.own.files import read_agent
    from connrl.storage import FileError

    m, _ = read_agent(Path(path), KINDS)
    env_id = m.get("env_id")
    if env_id is not None and (":" in env_id or env_id not in gym.registry):
        raise FileError(Path(path) / "agent.json", f"is {env_id!r}, not a registered Gymnasium environment (a "
                        "file never chooses code to import); give --env ENV_ID to choose the environment yourself",
                        "env_id")
    return env_id


def _saved_env_kwargs(path: Path) -> dict:
    """The env kwargs of the `connrl train` run an agent folder (or its best/ agent) came from; {} without one."""
    for folder in (path, path.parent) if path.name == "best" else (path,):
        file = folder / "settings.json"
        if file.exists():
            try:
                kwargs = _read_run_settings(file).get("env_kwargs", {})
            except ValueError as exc:
                raise SystemExit(f"connrl: {exc}") from None
            if not isinstance(kwargs, dict):
                raise SystemExit(f"connrl: {file}: env_kwargs must be a mapping, got {kwargs!r}")
            named = [k for k, v in kwargs.items() if isinstance(v, str) and ":" in v]
            if named:  # some wrappers import a 'module:Class' they are given: a file never chooses code to run
                raise SystemExit(f"connrl: {file}: env_kwargs {', '.join(named)} look like 'module:name' imports; a "
                                 "file never chooses code to import: give them yourself with --env-kwargs")
            return kwargs
    return {}


def cmd_evaluate(args) -> int:
    import numpy as np

    from connrl.own.api import episode_cap, evaluate, load

    try:
        env_id = args.env or _saved_env_id(args.path)
    except ValueError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    if not env_id:
        raise SystemExit(f"connrl: {args.path} holds an agent without an environment id; give --env ENV_ID")
    env_kwargs = {**_saved_env_kwargs(Path(args.path)), **_parse_options(args.env_kwargs, "--env-kwargs")}
    env = _make_env(env_id, env_kwargs)
    try:
        cap = episode_cap(env, args.max_episode_steps)
        agent = load(args.path, env)
        returns = evaluate(agent, env, args.episodes, seed=args.seed, max_episode_steps=cap)
    except ValueError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    print(_loaded(Path(args.path), agent))
    print(f"{env_id}: greedy return over {len(returns)} episodes (at most {cap} steps each): mean "
          f"{np.mean(returns):.2f}, min {min(returns):.2f}, max {max(returns):.2f}")
    return 0


def _loaded(path: Path, agent) -> str:
    """Which agent `connrl evaluate` loaded, and what its run's evaluation said of it."""
    e = agent.evaluation
    line = f"loaded {path}: {agent.kind}, trained {agent.steps_done} steps"
    if e is not None:
        what = "the run's best so far" if e["best"] else "not the run's best"
        after = "" if e["steps"] == agent.steps_done else f", {agent.steps_done - e['steps']} training steps before"
        line += (f"; evaluated at step {e['steps']}{after}: mean return {e['mean']:.2f} over {e['episodes']} "
                 f"episodes ({what} then)")
    best = path / "best" / "agent.json"
    if best.exists():
        line += f"; {best.parent} holds the run's best agent"
    return line


def add_evaluate_command(sub) -> None:
    """evaluate (connrl.own.api)."""
    s = sub.add_parser("evaluate", help="the greedy return of a saved agent", description="Load an agent saved "
                       "by `connrl train` (or Agent.save) and print its greedy return over --episodes episodes.")
    s.add_argument("path", help="the agent's folder")
    s.add_argument("--episodes", type=_positive_int, default=10)
    s.add_argument("--seed", type=_seed, default=0, help="seed of the first episode (default 0)")
    s.add_argument("--env", default=None, help="environment id (default: the one it was trained on)")
    s.add_argument("--env-kwargs", action="append", type=key_value, default=[], metavar="KEY=VALUE",
                   help="an argument of gymnasium.make (default: those it was trained with); repeat for several")
    s.add_argument("--max-episode-steps", type=_positive_int, default=None, metavar="N", help="cut each episode "
                   "at N steps (default: the environment's time limit, else 1000)")
    s.set_defaults(func=cmd_evaluate)
