"""Where Study 2's Q-agents fall short: food, deaths and starvation by representation, learning rate and input code.

    python scripts/ch4/study2_learner.py [--framework QCON] [--arms global:2 local:2 local:1 ...]
        [--seeds 100 101 102] [--coding pm|01] [--agent KEY=VALUE ...] [--plays 300]

Each arm is ``REPRESENTATION:LR_SCALE`` (Study 1 is global at 1; the thesis doubles every rate for Study 2, 4.3.3),
run with ``connrl.experiments.survival.run_survival`` (the full 4.3.1 protocol: 300 plays, 50 test environments
every 20) on each seed. Per arm, averaged over the seeds: the mean test curve (every 40 plays), the final food (last
three tests; mean ± standard deviation over the seeds, then each seed's), and how the last three tests' 50 plays
ended (all food, killed, starved), with the training plays' mean length and stuck steps over the last 50 plays.
``--coding 01`` feeds every input unit as 0/1 instead of the reconstruction's -0.5/+0.5 (Ch. 4 does not say which;
5.3.2's convention is ±0.5). ``--agent`` sets fields of ``connrl.tasks.survival.SurvivalAgentParams`` (VALUE is JSON:
``hidden=60``, ``stuck_boost=2.0``) for every arm. ``--plays`` trains longer than 4.3.1's 300 plays (tests stay
every 20), to tell a slow learner from one that stops short: the agent is the same, its schedules (temperature,
replay counts, teaching probability) still move over the first 300 plays and hold their end values after. The curve
is printed every 40 x (plays // 300) plays.
Development seeds only.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math

import numpy as np

import connrl.experiments.survival as survival
from connrl.envs.survival import SurvivalEnv
from connrl.experiments.spec import check_types
from connrl.experiments.survival import SurvivalParams, run_survival
from connrl.tasks.survival import SurvivalAgentParams, make_survival_agent


def arm(text: str) -> tuple[str, float]:
    rep, _, scale = text.partition(":")
    try:
        value = float(scale)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give REPRESENTATION:LR_SCALE, e.g. local:2") from None
    if rep not in ("global", "local") or not 0 < value < math.inf:
        raise argparse.ArgumentTypeError(f"{text!r}: representation global or local, lr scale a number > 0")
    return rep, value


RUN_LEVEL = ("framework", "representation", "lr_scale", "plays", "model")  # set by the arm and the protocol


def agent_overrides(items: list[str]) -> dict:
    """``--agent`` field=JSON pairs, each checked against its field's annotation by the sweep's own checker
    (``connrl.experiments.spec.check_types``); a bad one raises ValueError in one line."""
    defaults = SurvivalAgentParams()
    out = {}
    for item in items:
        key, _, value = item.partition("=")
        if key in RUN_LEVEL or not hasattr(defaults, key):
            allowed = [f.name for f in dataclasses.fields(defaults) if f.name not in RUN_LEVEL]
            raise ValueError(f"--agent {key!r}: not a field to set here; allowed: {', '.join(allowed)}")
        try:
            out[key] = json.loads(value)
        except json.JSONDecodeError:
            raise ValueError(f"--agent {item!r}: give field=JSON value, e.g. hidden=60") from None
    check_types(dataclasses.replace(defaults, **out))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--framework", default="QCON")
    ap.add_argument("--arms", nargs="+", type=arm, default=[("global", 1.0), ("local", 2.0), ("local", 1.0),
                                                           ("local", 0.5)])
    ap.add_argument("--seeds", nargs="+", type=int, default=[100, 101, 102])
    ap.add_argument("--coding", choices=["pm", "01"], default="pm")
    ap.add_argument("--agent", nargs="*", default=[], help="SurvivalAgentParams field=JSON value, for every arm")
    ap.add_argument("--plays", type=int, default=300, help="training plays (4.3.1: 300)")
    args = ap.parse_args()
    if min(args.seeds) < 0:
        ap.error(f"--seeds must be 0 or more, got {min(args.seeds)}")
    if not 60 <= args.plays <= 100_000 or args.plays % 20:
        ap.error(f"--plays must be a multiple of 20 (the test interval) in [60, 100000], got {args.plays}")
    try:
        overrides = agent_overrides(args.agent)
        for rep, scale in args.arms:  # every arm's agent is built once before anything runs
            env = SurvivalEnv(rep)
            env.reset(seed=0)
            params = SurvivalAgentParams(args.framework, rep, lr_scale=scale, **overrides)
            make_survival_agent(params, env, np.random.default_rng(0))
    except (TypeError, ValueError) as exc:
        ap.error(str(exc))
    build = survival._agent_params  # schedules over 4.3.1's 300 plays, however long the run
    survival._agent_params = lambda p: dataclasses.replace(build(p), plays=300, **overrides)
    if args.coding == "01":  # every unit of the observation is binary or coarse-coded at +-0.5
        observe = SurvivalEnv._observe
        SurvivalEnv._observe = lambda self: observe(self) + 0.5
    print(f"{args.framework}, inputs {'0/1' if args.coding == '01' else '-0.5/+0.5'}, agent {overrides or 'as is'}, "
          f"{args.plays} plays (schedules over 300), seeds {' '.join(map(str, args.seeds))}; last three tests' 50 "
          "plays: all food / killed / starved")
    for rep, scale in args.arms:
        curves, ends, train = [], [], []
        for seed in args.seeds:
            rows = run_survival(SurvivalParams(framework=args.framework, representation=rep, lr_scale=scale,
                                               train_plays=args.plays), np.random.default_rng(seed)).rows
            tests = [r for r in rows if r["kind"] == "test"]
            curves.append([t["food"] for t in tests])
            ends.append([np.mean([t[k] for t in tests[-3:]]) for k in ("all_food", "killed", "starved")])
            last = [r for r in rows if r["kind"] == "train"][-50:]
            train.append([np.mean([r[k] for r in last]) for k in ("steps", "stuck_steps")])
        curve, (all_food, killed, starved), (steps, stuck) = np.mean(curves, 0), np.mean(ends, 0), np.mean(train, 0)
        finals = [np.mean(c[-3:]) for c in curves]
        stride = 2 * max(1, args.plays // 300)
        print(f"{rep:<6} lr x{scale:<4g} curve {' '.join(f'{v:4.1f}' for v in curve[::stride])}  final "
              f"{np.mean(finals):5.2f} ± {np.std(finals):4.2f} ({' / '.join(f'{v:.2f}' for v in finals)})  ends "
              f"{all_food:4.1f} / {killed:4.1f} / {starved:4.1f}  training plays {steps:4.0f} steps, "
              f"{stuck:3.1f} stuck", flush=True)


if __name__ == "__main__":
    main()
