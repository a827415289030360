"""``connrl world-family``: the command line of connrl.experiments.world_family (issue 44's search of the robot
world's open details)."""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

from connrl.own.cli import _int_at_least, _positive_int, _writable, folder_name, one_writer

STAGES = ("search", "recheck", "predict", "all")


def cmd_world_family(args) -> int:
    from connrl.experiments import world_family as wf

    args.check_executor(args)
    if args.stage in ("search", "all") and importlib.util.find_spec("optuna") is None:
        raise SystemExit("connrl: world-family's search needs Optuna: pip install -e \".[tune]\" "
                         "(or pip install optuna)")
    out = Path(args.out)
    for stage, needs in (("recheck", "search.json"), ("predict", "recheck.json")):
        if args.stage == stage and not (out / needs).exists():
            raise SystemExit(f"connrl: stage {stage} reads {out / needs}, which is not there: run the stage before it "
                             f"(or --stage all)")
    _writable(out)
    out.mkdir(parents=True, exist_ok=True)
    run = {"workers": args.workers or os.cpu_count() or 1, "executor": args.executor, "address": args.address,
           "show": not args.quiet}
    with one_writer(out, "--out"):
        if args.stage in ("search", "all"):
            try:
                rows = wf.search(out, budget=args.budget, trials=args.trials, **run)
            except ValueError as exc:  # a log of another run length
                raise SystemExit(f"connrl: {exc}") from None
            print(f"search: {sum(r['accepted'] for r in rows)} of {len(rows)} worlds accepted ({out / 'search.csv'})")
        if args.stage in ("recheck", "all"):
            rows = wf.recheck(out, **run)
            print(f"recheck: {sum(r['accepted'] for r in rows)} of {len(rows)} accepted worlds accepted again "
                  f"({out / 'recheck.csv'})")
        if args.stage in ("predict", "all"):
            doc = wf.predict(out, **run)
            print(f"predict: {len(doc['worlds'])} worlds measured, pick: world {doc['pick']} "
                  f"({out / 'predictions.json'})")
    return 0


def add_world_family_command(sub, executor_options, check_executor) -> None:
    """``executor_options(parser)`` adds --executor and --address; ``check_executor(args)`` checks them (connrl.cli's,
    passed in: this module is imported by it)."""
    s = sub.add_parser("world-family", help="search the robot world's open details (issue 44)",
                       description="Measure the family of robot worlds the text allows (docs/RECONSTRUCTION.md, "
                       "'The robot world as a family'): search (TPE on the no-teaching DP target, development seeds "
                       "100-106), recheck (the accepted worlds on seeds 5100-5106), predict (teaching, lambda and copy "
                       "bound of the worlds accepted twice, and the pick). Every stage resumes where it stopped.")
    s.add_argument("--stage", choices=STAGES, default="all", help="which stage (default all, in order)")
    s.add_argument("--budget", type=_int_at_least(1, 10_000), default=160, help="worlds the search tries (default "
                   "160, the protocol's)")
    s.add_argument("--trials", type=_int_at_least(10, 10_000), default=300, help="trials per run (default 300, the "
                   "protocol's; fewer only for a smoke test: a search is resumed at its own length)")
    s.add_argument("--out", type=folder_name, default="runs/world-family", help="folder of the logs and run records "
                   "(default runs/world-family)")
    s.add_argument("--workers", type=_positive_int, default=None, help="worker processes (default: all cores)")
    s.add_argument("--quiet", action="store_true", help="no live progress display")
    executor_options(s)
    s.set_defaults(func=cmd_world_family, check_executor=check_executor)
