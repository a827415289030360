"""Command line: ``connrl list | run | reproduce | show | plot | results | sweep | teach | make-lessons |
train-behaviours | train | evaluate | tune``."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from connrl.cli_world import add_world_family_command
from connrl.experiments.spec import PROFILES
from connrl.own.cli import _positive_int, _seed, _writable, add_own_task_commands
from connrl.own.cli_evaluate import add_evaluate_command
from connrl.own.cli_tune import add_tune_command


def _experiments():
    from connrl.experiments.registry import all_experiments

    return all_experiments()


def _get(name: str):
    specs = _experiments()
    if name not in specs:
        raise SystemExit(f"connrl: unknown experiment {name!r}.\nAvailable: {', '.join(sorted(specs))}\n"
                         f"(`connrl list` describes them)")
    return specs[name]


def cmd_list(args) -> int:
    specs = _experiments()
    width = max(len(n) for n in specs)
    for name, spec in sorted(specs.items()):
        runs = {p: spec.profiles[p]["runs"] for p in PROFILES}
        print(f"{name:<{width}}  {spec.title}  [thesis {spec.section}; runs quick/full: "
              f"{runs['quick']}/{runs['full']}]")
    return 0


def _run_count(text: str) -> int:
    from connrl.experiments.store import MAX_RUNS

    n = _positive_int(text)
    if n > MAX_RUNS:
        raise argparse.ArgumentTypeError(f"must be at most {MAX_RUNS} runs per variant, got {n}")
    return n


def _damaged(path, reason: str) -> None:
    print(f"connrl: {path} is damaged ({reason}); redoing that run", file=sys.stderr)


def cmd_run(args) -> int:
    spec = _get(args.name)
    try:
        spec.resolve(args.profile, args.runs)
    except ValueError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    _check_executor(args)
    _writable(args.out)
    seed = spec.seed if args.seed is None else args.seed
    return _run_and_report(spec, args, profile=args.profile, runs=args.runs, seed=seed)


def cmd_reproduce(args) -> int:
    import time

    from connrl.experiments.registry import by_chapter
    from connrl.experiments.registry import chapters as known_chapters
    from connrl.report.page import write_results

    try:
        chapters = sorted({int(c) for c in args.chapters.split(",")})
    except ValueError:
        chapters = []
    known = known_chapters()
    if not chapters or not set(chapters) <= set(known):
        raise SystemExit(f"connrl: --chapters takes a comma-separated list of {', '.join(map(str, known))}, got "
                         f"{args.chapters!r}")
    specs = by_chapter(chapters)
    if args.only is not None:  # a subset of those chapters' experiments, by name
        names = [n.strip() for n in args.only.split(",") if n.strip()]
        known = {s.name for s in specs}
        unknown = [n for n in names if n not in known]
        if not names or unknown:
            raise SystemExit(f"connrl: --only takes a comma-separated list of experiments of chapters "
                             f"{','.join(map(str, chapters))} (see `connrl list`), got {args.only!r}"
                             + (f": unknown {', '.join(unknown)}" if unknown else ""))
        specs = [s for s in specs if s.name in names]
    _check_executor(args)
    for spec in specs:  # every profile is checked before the first run
        try:
            spec.resolve(args.profile, None)
        except ValueError as exc:
            raise SystemExit(f"connrl: {exc}") from None
    _writable(args.out)
    doc = Path(args.doc) if args.doc else Path(args.out) / "RESULTS.md"
    if doc.is_dir():
        raise SystemExit(f"connrl: --doc {doc} is a folder; it must name the results page's file (e.g. RESULTS.md)")
    _writable(doc.parent)  # before the runs: a page that cannot be written must not cost an hour of compute
    start = time.time()
    code = _run_pool(specs, args)
    if code:
        return code
    print(f"results: {write_results(Path(args.out), doc)}; chapters {', '.join(map(str, chapters))}, "
          f"{len(specs)} experiments, {time.time() - start:.0f} s")
    return 0


def _run_pool(specs, args) -> int:
    """Every experiment's runs as one pool, longest first; each experiment's plot and table as soon as it is done."""
    from connrl.experiments.runner import Batch, ExecutorError, run_experiments
    from connrl.report.plots import plot_experiment

    batches = [Batch(s, args.profile, s.full_runs if args.profile == "full" else None, s.seed) for s in specs]
    done, unplotted = [], []

    def on_done(outcome) -> None:
        spec = next(b.spec for b in batches if b.spec.name == outcome.summary["experiment"])
        done.append(spec.name)
        runs = f" --runs {spec.full_runs}" if args.profile == "full" and spec.full_runs else ""
        print(f"[{len(done)}/{len(batches)}] {spec.name} (alone: connrl run {spec.name} --profile {args.profile} "
              f"--seed {spec.seed}{runs}): {outcome.ran} run(s) executed, {outcome.reused} reused", flush=True)
        try:
            plot_experiment(spec, outcome.records, Path(args.out) / spec.name)
        except OSError as exc:  # said after the pool: the other experiments' runs go on
            unplotted.append(f"{spec.name}: {exc}")
        _print_summary(outcome.summary)

    try:
        run_experiments(batches, out=Path(args.out), workers=args.workers, show_progress=not args.quiet,
                        on_damaged=_damaged, executor=args.executor, address=args.address, title="thesis",
                        on_done=on_done)
    except KeyboardInterrupt:
        print("\ninterrupted: finished runs are saved; run the same command again to resume.", file=sys.stderr)
        return 130
    except OSError as exc:  # raised before any run by prepare_outputs (or a lock held by another command)
        raise SystemExit(f"connrl: {exc.strerror or exc}") from None
    except ExecutorError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    if unplotted:
        raise SystemExit("connrl: the runs are saved, but these plots could not be written: " + "; ".join(unplotted))
    return 0


def _run_and_report(spec, args, *, profile: str, runs: int | None, seed: int, mean_curve: bool = False) -> int:
    """Run (resuming finished runs), plot, and print the summary table; Ctrl-C keeps what finished."""
    import numpy as np

    from connrl.experiments.runner import ExecutorError, run_experiment
    from connrl.report.plots import plot_experiment

    try:
        outcome = run_experiment(spec, profile=profile, runs=runs, seed=seed, out=Path(args.out),
                                 workers=args.workers, show_progress=not args.quiet, on_damaged=_damaged,
                                 executor=getattr(args, "executor", "process"), address=getattr(args, "address", None))
    except KeyboardInterrupt:
        print("\ninterrupted: finished runs are saved; run the same command again to resume.", file=sys.stderr)
        return 130
    except OSError as exc:  # raised before any run by prepare_outputs
        raise SystemExit(f"connrl: {exc.strerror or exc}") from None
    except ExecutorError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    try:
        plots = plot_experiment(spec, outcome.records, Path(args.out) / spec.name)
    except OSError as exc:
        raise SystemExit(f"connrl: the runs are saved, but the plot could not be written: {exc}") from None
    _print_summary(outcome.summary)
    curves = [r["curve_y"] for r in sorted(outcome.records, key=lambda r: r["seed"])]
    if mean_curve and curves and len({len(c) for c in curves}) == 1 and curves[0]:
        xs, mean = outcome.records[0]["curve_x"], np.mean(np.array(curves, dtype=float), axis=0)
        idx = np.unique(np.linspace(0, len(xs) - 1, min(11, len(xs))).round().astype(int))
        print("mean curve: " + ", ".join(f"{xs[i]:g}: {mean[i]:.3g}" for i in idx))
    print(f"\n{outcome.ran} run(s) executed, {outcome.reused} reused from earlier; "
          f"{outcome.summary['timing']['wall_time_s']:.1f} s")
    print(f"summary: {outcome.summary_path}")
    for p in plots:
        print(f"plot:    {p}")
    return 0


def _print_summary(summary: dict) -> None:
    """Our numbers beside the thesis's, one line per quantity: nothing is cut at any terminal width."""
    from connrl.report.page import fmt, meets, per_run

    caveat = summary["profile"] != "full"
    print(f"{summary['experiment']}: {summary['profile']} profile"
          + (" (not the thesis's protocol: that is --profile full)" if caveat else " (the thesis's protocol)")
          + f", {summary['runs_per_variant']} run(s) per variant, seeds from {summary['base_seed']}")
    for label, v in summary["variants"].items():
        print(f"  {label}")
        for name, q in v["quantities"].items():
            better = {"lower": "lower is better", "higher": "higher is better"}.get(q.get("better"), "")
            print(f"    {name} ({better}): ours {fmt(q['mean'])} (per run: {per_run(q, v.get('diverged'))}); "
                  f"thesis {fmt(q['thesis'])}; meets thesis: "
                  f"{meets(q, summary['profile'], False, summary['runs_per_variant'], summary.get('protocol_runs'))}")


def cmd_plot(args) -> int:
    from connrl.report.plots import plot_from_disk

    if any((Path(n) / "progress.csv").exists() for n in args.name):  # `connrl train` folders: their training logs
        return _plot_training(args.name, args.to)
    if len(args.name) > 1:
        raise SystemExit("connrl: several names are `connrl train` folders, each holding a progress.csv; an "
                         "experiment is plotted one at a time")
    args.name = args.name[0]
    from connrl.experiments.registry import all_experiments

    if args.name not in all_experiments() and (Path(args.name).is_dir() or os.sep in args.name):
        raise SystemExit(f"connrl: {args.name} holds no progress.csv; `connrl plot` draws a `connrl train` folder "
                         "(its progress.csv) or a stored experiment by name (`connrl list`)")
    spec = _get(args.name)
    from connrl.experiments.store import DamagedFile

    try:
        paths = plot_from_disk(spec, Path(args.out))
    except (FileNotFoundError, DamagedFile) as exc:
        raise SystemExit(f"connrl: {exc}") from None
    except OSError as exc:
        raise SystemExit(f"connrl: the plot could not be written: {exc}") from None
    for p in paths:
        print(p)
    return 0


def _plot_training(folders: list[str], to: str | None) -> int:
    from connrl.own.plots import plot_training, write_runs_curve

    missing = [f for f in folders if not (Path(f) / "progress.csv").exists()]
    if missing:
        raise SystemExit(f"connrl: {', '.join(missing)} holds no progress.csv (a `connrl train` folder has one)")
    try:
        if len(folders) == 1 and to is None:
            print(plot_training(Path(folders[0])))
        else:
            out = Path(to) if to else Path(os.path.commonpath([Path(f).resolve() for f in folders])) / "curves.png"
            print(write_runs_curve([Path(f) for f in folders], out))
    except (ValueError, OSError) as exc:
        raise SystemExit(f"connrl: {exc}") from None
    return 0


def cmd_show(args) -> int:
    spec = _get(args.name)
    from connrl.experiments.store import DamagedFile, load_summary

    p = Path(args.out) / spec.name / "summary.json"
    if not p.exists():
        raise SystemExit(f"connrl: {p} not found: run `connrl run {spec.name}` first")
    try:
        _print_summary(load_summary(p, spec.name))
    except DamagedFile as exc:
        raise SystemExit(f"connrl: {exc}") from None
    return 0


def cmd_params(args) -> int:
    from connrl.report.params import class_tables, experiment_table

    print(experiment_table(_get(args.name)) if args.name else class_tables(_experiments()), end="")
    return 0


def _add_params_command(sub) -> None:
    s = sub.add_parser("params", help="print an experiment's parameters", description="Print, as Markdown, an "
                       "experiment's parameters (value, allowed values, where the thesis states it, what sets it) "
                       "or, without NAME, every parameter class's (docs/PARAMETERS.md).")
    s.add_argument("name", nargs="?", help="experiment name (default: every parameter class)")
    s.set_defaults(func=cmd_params)


def cmd_teach(args) -> int:
    from connrl.tasks.teach import TEACH_TARGETS, teach

    if args.target not in TEACH_TARGETS:
        raise SystemExit(f"connrl: unknown teach target {args.target!r}; available: {', '.join(TEACH_TARGETS)}")
    return teach(args.target, out=Path(args.out) if args.out else None, seed=args.seed)


def cmd_sweep(args) -> int:
    from connrl.experiments.sweep import parse_seeds, sweep_spec

    spec = _get(args.name)
    try:
        first, stop = parse_seeds(args.seeds)
        sweep = sweep_spec(spec, args.set or [], args.variant)
    except ValueError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    _writable(args.out)
    print(sweep.title)
    return _run_and_report(sweep, args, profile="full", runs=stop - first, seed=first, mean_curve=True)


def cmd_make_lessons(args) -> int:
    if args.world == "robot":
        from connrl.tasks.recharge import write_chg_lessons
        from connrl.tasks.robot import write_taught_lessons

        paths = [*write_taught_lessons(seed=args.seed), write_chg_lessons(seed=args.seed)]
    else:
        from connrl.tasks.survival import write_taught_lessons

        paths = write_taught_lessons(seed=args.seed)
    for path in paths:
        print(path)
    return 0


def cmd_train_behaviours(args) -> int:
    from connrl.experiments.behaviours import train_library
    from connrl.tasks.behaviours import LIBRARY_DIR

    if args.out and args.replace_shipped:
        raise SystemExit("connrl: give either --out DIR or --replace-shipped, not both")
    out = LIBRARY_DIR if args.replace_shipped else Path(args.out or "runs/behaviours")
    _writable(out)
    index = train_library(out, seed=args.seed, trials=args.trials, workers=args.workers or 2)
    for task, m in index.items():
        print(f"{task}: {m['trials']} trials, final test {m['final_test_performance']:.2f} reinforcement/step, "
              f"where Ch. 6 uses it {m['serve_rate']:.2f}")
    print(f"library: {out}" + ("" if args.replace_shipped else " (the Ch. 6 runs use the shipped library, "
                                "connrl/data/behaviours/; --replace-shipped writes there)"))
    return 0


def cmd_results(args) -> int:
    from connrl.report.page import write_results

    out = Path(args.out)
    stored = sorted(p.parent.name for p in out.glob("*/summary.json")) if out.is_dir() else []
    if not stored:
        raise SystemExit(f"connrl: no stored results in {out} (no OUT/NAME/summary.json): run `connrl run NAME` "
                         "first, or give --out the folder your runs are in")
    doc = Path(args.doc) if args.doc else out / "RESULTS.md"
    if doc.is_dir():
        raise SystemExit(f"connrl: cannot write to {doc}: it is a folder; --doc takes a Markdown file")
    _writable(doc.parent)
    total = len(_experiments())
    if len(stored) < total:
        print(f"connrl: warning: {len(stored)} of {total} experiments have stored results in {out}; the page "
              "lists the others as not yet run", file=sys.stderr)
    path = write_results(out, doc)
    print(path)
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="connrl", description="Reproduce Lin (1993), Reinforcement Learning for "
                                "Robots Using Neural Networks, and use its techniques on Gymnasium tasks.")
    sub = p.add_subparsers(dest="command", required=True)
    _add_experiment_commands(sub)
    _add_params_command(sub)
    _add_tool_commands(sub)
    add_own_task_commands(sub)
    add_evaluate_command(sub)
    add_tune_command(sub)
    add_world_family_command(sub, _executor_options, _check_executor)
    return p


def _executor_options(s) -> None:
    s.add_argument("--executor", default="process", help="process: worker processes here (default); ray: Ray "
                   "tasks, on a local instance or the cluster at --address (pip install -e \".[ray]\")")
    s.add_argument("--address", default=None, help="a Ray cluster's head, HOST:PORT (with --executor ray); "
                   "its token, if it wants one, is taken from ~/.ray/auth_token or RAY_AUTH_TOKEN")


def _check_executor(args) -> None:
    from connrl.experiments.runner import ExecutorError, check_executor, check_ray_cluster

    try:
        check_executor(args.executor)
    except ValueError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    if args.address and args.executor != "ray":
        raise SystemExit("connrl: --address is for --executor ray")
    if args.address:
        try:  # before any run: Ray itself would retry a dead address for minutes, a refused token for 20 s
            check_ray_cluster(args.address)
        except ExecutorError as exc:
            raise SystemExit(f"connrl: {exc}") from None


def _add_experiment_commands(sub) -> None:
    """list, run, plot, show, teach."""
    s = sub.add_parser("list", help="list the experiments", description="List every experiment with its "
                       "thesis section and run counts.")
    s.set_defaults(func=cmd_list)

    s = sub.add_parser("run", help="run an experiment", description="Run an experiment's independent runs in "
                       "parallel, write OUT/NAME/summary.json and a learning-curve plot. Finished runs are "
                       "kept: re-running the same command resumes after Ctrl-C.")
    s.add_argument("name", help="experiment name (see `connrl list`)")
    s.add_argument("--profile", choices=PROFILES, default="quick",
                   help="quick: minutes, a first look (default); full: the thesis's protocol; tiny: a smoke test")
    s.add_argument("--runs", type=_run_count, default=None, help="runs per variant (overrides the profile)")
    s.add_argument("--seed", type=_seed, default=None,
                   help="base seed; run i uses seed+i (default: the experiment's own first seed, as `connrl reproduce` "
                        "uses: 0, but 100 for robot-dp-calibration, 6000 for robot-dp-fresh, 2000 for "
                        "survival-study1-fresh and survival-study2-fresh)")
    s.add_argument("--out", default="runs", help="output directory (default ./runs)")
    s.add_argument("--workers", type=_positive_int, default=None, help="worker processes (default: all cores)")
    s.add_argument("--quiet", action="store_true", help="no live progress display")
    _executor_options(s)
    s.set_defaults(func=cmd_run)

    s = sub.add_parser("reproduce", help="run every experiment of the thesis's chapters, then the results page",
                       description="`connrl run` each experiment of the chosen chapters (on the seeds its stored "
                       "results use), resuming what is stored, then write the results page.")
    s.add_argument("--chapters", default="4,5,6,7,8", help="comma-separated chapters (default 4,5,6,7,8)")
    s.add_argument("--only", default=None, metavar="NAME,...", help="only these experiments of the chapters (the "
                   "page is still written from everything stored in --out)")
    s.add_argument("--profile", choices=PROFILES, default="quick", help="tiny, quick (default) or full")
    s.add_argument("--out", default="runs", help="output directory (default ./runs)")
    s.add_argument("--doc", default=None, help="results page to write (default OUT/RESULTS.md)")
    s.add_argument("--workers", type=_positive_int, default=None, help="worker processes (default: all cores)")
    s.add_argument("--quiet", action="store_true", help="no live progress display")
    _executor_options(s)
    s.set_defaults(func=cmd_reproduce)

    s = sub.add_parser("plot", help="redraw an experiment's or a trained agent's plot", description="Redraw "
                       "OUT/NAME/curve.png and .svg from the stored runs of the latest `connrl run NAME`; given the "
                       "folder of a `connrl train` run, its curve.png from its progress.csv; given several, their "
                       "curves side by side with their mean and spread by steps (curves.png in their common folder, "
                       "or --to FILE).")
    s.add_argument("name", nargs="+", help="experiment name, or one or more `connrl train` folders")
    s.add_argument("--out", default="runs", help="output directory of the run (default ./runs)")
    s.add_argument("--to", default=None, metavar="FILE", help="where the curves of `connrl train` folders go")
    s.set_defaults(func=cmd_plot)

    s = sub.add_parser("show", help="print an experiment's summary table", description="Print the table of "
                       "OUT/NAME/summary.json: our numbers beside the thesis's.")
    s.add_argument("name", help="experiment name")
    s.add_argument("--out", default="runs", help="output directory of the run (default ./runs)")
    s.set_defaults(func=cmd_show)

    s = sub.add_parser("teach", help="record a taught lesson by playing", description="Play a task from the "
                       "keyboard and save the trial as a taught lesson (JSON lesson file, see "
                       "connrl.core.lesson_files).")
    s.add_argument("target", help="what to teach (e.g. survival, robot-dp)")
    s.add_argument("--out", default=None, help="lesson file to write (default: lessons/TARGET-<time>.json)")
    s.add_argument("--seed", type=_seed, default=0, help="environment seed (default 0)")
    s.set_defaults(func=cmd_teach)


def _add_tool_commands(sub) -> None:
    """sweep, make-lessons, train-behaviours, results."""
    s = sub.add_parser("sweep", help="run an experiment's setting with overrides over many seeds",
                       description="Run the experiment's full-profile parameters (or one variant's) with --set "
                       "overrides, one run per seed A..B-1, seeded as `connrl run` seeds its runs. Unknown keys "
                       "and bad values are refused before any compute. Runs are stored and resumable under "
                       "OUT/sweep-NAME-HASH/; give the same command again to print the table again.")
    s.add_argument("name", help="experiment name (see `connrl list`)")
    s.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a parameter; VALUE is JSON (1, 0.5, true, null, [10, 30], {\"hq\": 12}) "
                   "or a plain string; repeat for several")
    s.add_argument("--seeds", required=True, metavar="A:B", help="seeds A..B-1, one run each (e.g. 100:107)")
    s.add_argument("--variant", default=None, help="start from this variant's parameters (its label)")
    s.add_argument("--out", default="runs", help="output directory (default ./runs)")
    s.add_argument("--workers", type=_positive_int, default=None, help="worker processes (default: all cores)")
    s.add_argument("--quiet", action="store_true", help="no live progress display")
    s.set_defaults(func=cmd_sweep)

    s = sub.add_parser("make-lessons", help="regenerate the shipped taught lessons",
                       description="Rewrite connrl/data/lessons/ for a world from its scripted teacher "
                       "(deterministic: the same seed gives the same files).")
    s.add_argument("world", choices=("robot", "survival"), help="robot: robot-{dp,dk,wfl,wfr}.json; survival: "
                   "survival-{global,local}.json")
    s.add_argument("--seed", type=_seed, default=0, help="teacher seed (default 0, the shipped files)")
    s.set_defaults(func=cmd_make_lessons)

    s = sub.add_parser("train-behaviours", help="train the Ch. 6 behaviour library (DK, DP, WFL, WFR)",
                       description="Train Ch. 5's QCON-T for each behaviour (deterministic given --seed) and store "
                       "it as NPZ + JSON with its provenance, plus library.json with each one's rate where Ch. 6 "
                       "uses it. It writes under runs/behaviours unless told otherwise; --replace-shipped "
                       "rewrites the library the Ch. 6 runs use, connrl/data/behaviours/ (its digest is in "
                       "their run folders: stored Ch. 6 runs are then redone).")
    s.add_argument("--out", default=None, help="library folder (default: runs/behaviours)")
    s.add_argument("--replace-shipped", action="store_true",
                   help="write into the shipped library, connrl/data/behaviours/, which the Ch. 6 runs use")
    s.add_argument("--seed", type=_seed, default=0, help="seed of the first behaviour (default 0, the shipped one)")
    s.add_argument("--trials", type=_positive_int, default=None,
                   help="trials per behaviour (default: the plan's 1500)")
    s.add_argument("--workers", type=_positive_int, default=None, help="worker processes (default 2)")
    s.set_defaults(func=cmd_train_behaviours)

    s = sub.add_parser("results", help="write a results page (OUT/RESULTS.md) from stored summaries",
                       description="Collect every OUT/*/summary.json into a Markdown results page, by default "
                       "OUT/RESULTS.md beside the runs (figures in OUT/figures/). The shipped page is rewritten "
                       "only when asked: --doc docs/RESULTS.md.")
    s.add_argument("--out", default="runs", help="directory holding the experiments' outputs (default ./runs)")
    s.add_argument("--doc", default=None, help="Markdown file to write (default OUT/RESULTS.md; the shipped page "
                   "is docs/RESULTS.md)")
    s.set_defaults(func=cmd_results)


def main(argv: list[str] | None = None) -> int:
    from connrl.core.lesson_files import LessonFileError
    from connrl.storage import FileError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (LessonFileError, FileError) as exc:  # a file connrl read and refused: one line naming it
        raise SystemExit(f"connrl: {exc}") from None
    except BrokenPipeError:  # e.g. `connrl show NAME | head`: the reader left, nothing is wrong
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:  # a full disk, a folder gone read-only, ...: one line naming the file
        where = f"{exc.filename}: " if exc.filename else ""
        raise SystemExit(f"connrl: {where}{exc.strerror or exc}") from None
    except MemoryError:  # the readers' limits keep connrl's own files far below this; say so, not a traceback
        raise SystemExit("connrl: out of memory; the command needs more memory than this machine allows") from None


if __name__ == "__main__":
    raise SystemExit(main())
