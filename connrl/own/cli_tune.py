"""``connrl tune ENV``: the command line of connrl.own.tune (a search over an agent's settings)."""

from __future__ import annotations

import sys
from argparse import SUPPRESS, ArgumentDefaultsHelpFormatter
from functools import partial
from pathlib import Path

from connrl.own.cli import (
    MAX_STEPS,
    _int_at_least,
    _make_env,
    _parse_options,
    _positive_int,
    _seed,
    _writable,
    folder_name,
    key_value,
    one_writer,
)


class _Defaults(ArgumentDefaultsHelpFormatter):
    """Help that shows each default an option has (not the None or [] of an option with none)."""

    def _get_help_string(self, action):
        if action.default in (None, [], SUPPRESS) or isinstance(action.default, bool):
            return action.help
        return super()._get_help_string(action)


def cmd_tune(args) -> int:
    from connrl.own.api import options_from
    from connrl.own.tune import DEFAULT_SPACE, check_space, parse_dimension, run_search

    kind = args.agent
    try:
        fixed = _parse_options(args.option)
        options_from(fixed)
        space = [parse_dimension(t) for t in (args.space or DEFAULT_SPACE)]
        clash = sorted({d.name for d in space} & set(fixed))
        if clash:
            raise ValueError(f"{', '.join(clash)} is both searched (--space) and fixed (--option)")
        check_space(space, fixed)
    except (ValueError, TypeError) as exc:
        raise SystemExit(f"connrl: {exc}") from None
    env_kwargs = _parse_options(args.env_kwargs, "--env-kwargs")
    _make_env(args.env_id, env_kwargs)  # an unknown id or bad kwargs: one line before any training
    name = args.env_id.replace("/", "-").replace(":", "-")
    out = Path(args.out or f"runs/tune/{name}-{kind}")
    _writable(out)
    if args.sampler == "tpe" and (args.workers > 1 or args.pruner != "none"):
        raise SystemExit("connrl: --workers and --pruner go with --sampler random; TPE asks for each trial after the "
                         "last one's whole result (--workers 1, --pruner none)")
    study = {"env_id": args.env_id, "env_kwargs": env_kwargs, "agent": kind, "steps": args.steps,
             "seeds": args.seeds, "eval_episodes": args.eval_episodes, "trials": args.trials, "fixed": fixed,
             "space": [f"{d.name}={d.describe()}" for d in space], "sampler": args.sampler, "seed": args.study_seed,
             "pruner": args.pruner, "draws": "unrepeated"}  # a search drawn before planned() is not resumed by it
    with one_writer(out, "--out"):
        try:
            trials = run_search(partial(_make_env, args.env_id, env_kwargs), study, space, out, args.sampler,
                                workers=args.workers, pruner=args.pruner)
        except ValueError as exc:
            raise SystemExit(f"connrl: {exc}") from None
        except KeyboardInterrupt:
            print(f"\nconnrl: interrupted; the finished trials are in {out / 'trials.csv'} and the same command "
                  "resumes", file=sys.stderr)
            return 130
        return _write_best(out, study, trials, args.train_steps)


def _write_best(out: Path, study: dict, trials: list[dict], train_steps: int | None) -> int:
    """best.yml: the best whole trial's settings; its n_timesteps the training budget (``--train-steps``, else the
    shipped settings file's for the task, else none: `connrl train`'s default), never the search's budget."""
    from connrl.own.settings import settings_yaml, task_settings
    from connrl.storage import atomic_write_text

    best = trials[0]
    if len(best["scores"]) < len(study["seeds"]):
        raise SystemExit("connrl: every trial was pruned; run more trials, or --pruner none")
    if train_steps is None:
        shipped, _ = task_settings(study["env_id"], study["agent"])
        train_steps = (shipped or {}).get("n_timesteps")
    comment = (f"connrl tune {study['env_id']} --agent {study['agent']}: best of {len(trials)} trials, mean greedy "
               f"return {best['mean']:.2f} over tuning seeds {study['seeds']}, each agent trained {study['steps']} "
               f"steps in the search\nn_timesteps is the training budget (--train-steps), not the search's; check "
               "the settings on other seeds before you report them")
    atomic_write_text(out / "best.yml", settings_yaml(study["env_id"], train_steps, study["env_kwargs"],
                                                      {**study["fixed"], **best["params"]}, comment))
    print(f"best: trial {best['trial'] + 1}, {best['params']}, mean greedy return {best['mean']:.2f}")
    print(f"wrote {out / 'best.yml'}: `connrl train {study['env_id']} --agent {study['agent']} --hyperparams "
          f"{out / 'best.yml'} --seed S` trains with it")
    return 0


def _seed_list(text: str) -> list[int]:
    import argparse

    try:
        seeds = [int(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seeds like 1000,1001, got {text!r}") from None
    if not seeds or min(seeds) < 0 or len(set(seeds)) != len(seeds):
        raise argparse.ArgumentTypeError(f"seeds must be distinct whole numbers >= 0, got {text!r}")
    return seeds


def add_tune_command(sub) -> None:
    """tune (connrl.own.tune)."""
    kinds = ("QCON", "QCON-R", "AHCON", "AHCON-R", "window-Q", "recurrent-Q")  # connrl.own.api.KINDS without a teacher
    s = sub.add_parser("tune", help="search an agent's settings for a task",
                       formatter_class=_Defaults, description="Search AgentOptions "
                       "for ENV_ID: each trial trains one agent per tuning seed and scores its mean greedy return "
                       "(connrl/own/tune.py). Writes OUT/trials.csv, OUT/study.json and OUT/best.yml (a settings file "
                       "for `connrl train --hyperparams`); the same command resumes an interrupted search.")
    s.add_argument("env_id", help="a Gymnasium environment id")
    s.add_argument("--agent", default="QCON-R", choices=kinds, metavar="AGENT",
                   help=f"the learner: {', '.join(kinds)}")
    s.add_argument("--space", action="append", default=None, metavar="NAME=SPEC", help="a searched option: "
                   "NAME=a,b,c or NAME=low:high[:log]; repeat for several (none given: lr, hidden, lam and "
                   "lessons_per_trial over connrl.own.tune.DEFAULT_SPACE)")
    s.add_argument("--option", action="append", type=key_value, default=[], metavar="KEY=VALUE",
                   help="a fixed option (an AgentOptions field); repeat for several")
    s.add_argument("--trials", type=_int_at_least(1, 10_000), default=20, help="settings tried")
    s.add_argument("--steps", type=_int_at_least(1, MAX_STEPS), default=20_000, help="training steps per agent in "
                   "the search")
    s.add_argument("--train-steps", type=_int_at_least(1, MAX_STEPS), default=None, help="the training budget "
                   "best.yml gives `connrl train` (none given: the shipped settings file's for the task, else train's "
                   "default)")
    s.add_argument("--workers", type=_int_at_least(1, 256), default=1, help="trials at once, each in a process "
                   "(--sampler random)")
    s.add_argument("--pruner", choices=("none", "median"), default="none", help="median: stop a trial whose running "
                   "mean after a seed is below the median of the whole trials' (once 4 are whole)")
    s.add_argument("--seeds", type=_seed_list, default="1000,1001", help="tuning seeds, comma-separated, apart "
                   "from those you report")
    s.add_argument("--eval-episodes", type=_positive_int, default=5, help="greedy episodes that score an agent")
    s.add_argument("--sampler", choices=("random", "tpe"), default="random", help="random (built in) or tpe "
                   "(Optuna: pip install 'connrl[tune]')")
    s.add_argument("--study-seed", type=_seed, default=0, help="seed of the sampler")
    s.add_argument("--env-kwargs", action="append", type=key_value, default=[], metavar="KEY=VALUE",
                   help="an argument of gymnasium.make(ENV_ID, ...); repeat for several")
    s.add_argument("--out", type=folder_name, default=None, help="folder (none given: runs/tune/ENV-AGENT)")
    s.set_defaults(func=cmd_tune)
