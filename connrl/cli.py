"""Command line: ``connrl list | run | reproduce | show | plot | results | sweep | teach | make-lessons |
train-behaviours | train | evaluate``."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from connrl.experiments.spec import PROFILES


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


def _run_count(text: str) -> int:
    from connrl.experiments.store import MAX_RUNS

    n = _positive_int(text)
    if n > MAX_RUNS:
        raise argparse.ArgumentTypeError(f"must be at most {MAX_RUNS} runs per variant, got {n}")
    return n


def _writable(folder) -> None:
    """Refuse an output folder we cannot write in before any run starts (one line)."""
    from connrl.storage import check_writable_dir

    if not str(folder).strip():
        raise SystemExit("connrl: --out must name a folder, got an empty string")
    try:
        check_writable_dir(folder)
    except OSError as exc:
        raise SystemExit(f"connrl: cannot write to {folder}: {exc.strerror or exc}") from None


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
    return _run_and_report(spec, args, profile=args.profile, runs=args.runs, seed=args.seed)


def cmd_reproduce(args) -> int:
    import time

    from connrl.experiments.registry import CHAPTERS, by_chapter
    from connrl.report.page import write_results

    try:
        chapters = sorted({int(c) for c in args.chapters.split(",")})
    except ValueError:
        chapters = []
    known = sorted(set(CHAPTERS.values()))
    if not chapters or not set(chapters) <= set(known):
        raise SystemExit(f"connrl: --chapters takes a comma-separated list of {', '.join(map(str, known))}, got "
                         f"{args.chapters!r}")
    specs = by_chapter(chapters)
    _check_executor(args)
    for spec in specs:  # every profile is checked before the first run
        try:
            spec.resolve(args.profile, None)
        except ValueError as exc:
            raise SystemExit(f"connrl: {exc}") from None
    _writable(args.out)
    start = time.time()
    for k, spec in enumerate(specs, 1):
        print(f"[{k}/{len(specs)}] connrl run {spec.name} --profile {args.profile} --seed {spec.seed}", flush=True)
        code = _run_and_report(spec, args, profile=args.profile, runs=None, seed=spec.seed)
        if code:
            return code
    doc = Path(args.doc) if args.doc else Path(args.out) / "RESULTS.md"
    _writable(doc.parent)
    print(f"results: {write_results(Path(args.out), doc)}; chapters {', '.join(map(str, chapters))}, "
          f"{len(specs)} experiments, {time.time() - start:.0f} s")
    return 0


def _run_and_report(spec, args, *, profile: str, runs: int | None, seed: int, mean_curve: bool = False) -> int:
    """Run (resuming finished runs), plot, and print the summary table; Ctrl-C keeps what finished."""
    import numpy as np

    from connrl.experiments.runner import run_experiment
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
    try:
        plots = plot_experiment(spec, outcome.records, Path(args.out) / spec.name)
    except OSError as exc:
        raise SystemExit(f"connrl: the runs are saved, but the plot could not be written: {exc}") from None
    _print_summary(outcome.summary)
    curves = [r["curve_y"] for r in sorted(outcome.records, key=lambda r: r["seed"])]
    if mean_curve and curves and len({len(c) for c in curves}) == 1 and curves[0]:
        xs, mean = outcome.records[0]["curve_x"], np.mean(curves, axis=0)
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

    out = Path(args.out) if args.out else LIBRARY_DIR
    _writable(out)
    index = train_library(out, seed=args.seed, trials=args.trials, workers=args.workers or 2)
    for task, m in index.items():
        print(f"{task}: {m['trials']} trials, final test {m['final_test_performance']:.2f} reinforcement/step, "
              f"where Ch. 6 uses it {m['serve_rate']:.2f}")
    print(f"library: {out}")
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


def _make_env(env_id: str):
    import gymnasium as gym

    import connrl  # noqa: F401  (registers the thesis's worlds)
    try:
        return gym.make(env_id)
    except gym.error.Error as exc:
        raise SystemExit(f"connrl: cannot make environment {env_id!r}: {exc}") from None


def cmd_train(args) -> int:
    import json

    import matplotlib.pyplot as plt

    from connrl.api import make_agent

    options = {}
    for item in args.option:
        key, sep, value = item.partition("=")
        if not sep:
            raise SystemExit(f"connrl: --option expects key=value, got {item!r}")
        try:
            options[key] = json.loads(value)
        except json.JSONDecodeError:
            options[key] = value
    out = Path(args.save or f"runs/train/{args.env_id.replace('/', '-')}-{args.agent}-seed{args.seed}")
    _writable(out)
    env = _make_env(args.env_id)
    returns = []
    try:
        agent = make_agent(env, args.agent, seed=args.seed, **options)
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
        env_id = args.env or json.loads((Path(args.path) / "agent.json").read_text()).get("env_id")
    except (OSError, json.JSONDecodeError):
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


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="connrl", description="Reproduce Lin (1993), Reinforcement Learning for "
                                "Robots Using Neural Networks, and use its techniques on Gymnasium tasks.")
    sub = p.add_subparsers(dest="command", required=True)
    _add_experiment_commands(sub)
    _add_tool_commands(sub)
    _add_own_task_commands(sub)
    return p


def _executor_options(s) -> None:
    s.add_argument("--executor", default="process", help="process: worker processes here (default); ray: Ray "
                   "tasks, on a local instance or the cluster at --address (pip install -e \".[ray]\")")
    s.add_argument("--address", default=None, help="a Ray cluster's head, HOST:PORT (with --executor ray)")


def _check_executor(args) -> None:
    from connrl.experiments.runner import check_executor

    try:
        check_executor(args.executor)
    except ValueError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    if args.address and args.executor != "ray":
        raise SystemExit("connrl: --address is for --executor ray")


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
    s.add_argument("--seed", type=_seed, default=0, help="base seed; run i uses seed+i (default 0)")
    s.add_argument("--out", default="runs", help="output directory (default ./runs)")
    s.add_argument("--workers", type=_positive_int, default=None, help="worker processes (default: all cores)")
    s.add_argument("--quiet", action="store_true", help="no live progress display")
    _executor_options(s)
    s.set_defaults(func=cmd_run)

    s = sub.add_parser("reproduce", help="run every experiment of the thesis's chapters, then the results page",
                       description="`connrl run` each experiment of the chosen chapters (on the seeds its stored "
                       "results use), resuming what is stored, then write the results page.")
    s.add_argument("--chapters", default="4,5,6,7,8", help="comma-separated chapters (default 4,5,6,7,8)")
    s.add_argument("--profile", choices=PROFILES, default="quick", help="tiny, quick (default) or full")
    s.add_argument("--out", default="runs", help="output directory (default ./runs)")
    s.add_argument("--doc", default=None, help="results page to write (default OUT/RESULTS.md)")
    s.add_argument("--workers", type=_positive_int, default=None, help="worker processes (default: all cores)")
    s.add_argument("--quiet", action="store_true", help="no live progress display")
    _executor_options(s)
    s.set_defaults(func=cmd_reproduce)

    s = sub.add_parser("plot", help="redraw an experiment's plot", description="Redraw OUT/NAME/curve.png and "
                       ".svg from the stored runs of the latest `connrl run NAME`.")
    s.add_argument("name", help="experiment name")
    s.add_argument("--out", default="runs", help="output directory of the run (default ./runs)")
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
                       "uses it. Without --out this rewrites the shipped library, connrl/data/behaviours/.")
    s.add_argument("--out", default=None, help="library folder (default: the shipped connrl/data/behaviours)")
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


def _add_own_task_commands(sub) -> None:
    """train, evaluate (connrl.api)."""
    s = sub.add_parser("train", help="train a thesis learner on any Gymnasium task", description="Train QCON, "
                       "QCON-R, window-Q or recurrent-Q on ENV_ID with inputs and values scaled from the task "
                       "(connrl.api), then save it (agent.json, agent.npz) and its learning curve (curve.png).")
    s.add_argument("env_id", help="a Gymnasium environment id, e.g. CartPole-v1 or connrl/PoleBalancing-v0")
    s.add_argument("--agent", default="QCON-R", help="QCON, QCON-R (default), window-Q or recurrent-Q")
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


def main(argv: list[str] | None = None) -> int:
    from connrl.core.lesson_files import LessonFileError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except LessonFileError as exc:
        raise SystemExit(f"connrl: {exc}") from None
    except BrokenPipeError:  # e.g. `connrl show NAME | head`: the reader left, nothing is wrong
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
