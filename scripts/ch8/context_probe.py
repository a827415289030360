"""What do the recurrent Q-nets' context units hold? (issue 28; ours)

Trains Ch. 8's recurrent learner (``integration``'s "Exp. 2: recurrent-Q, no X-Y", with ``--set`` overrides) on
development seeds, plays greedy tests from every room, learning off, and measures on held-out trials (half of the
tests fit, the other half score):

  - R^2: the share of the context's variance a least-squares readout explains from (a) the behaviour chosen at the
    step before (c_t is made by that behaviour's net, 7.4) and (b) the current room (which the inputs show anyway);
  - in room C only: how well a linear classifier tells "came into room C through door B" from the context, from the
    14 inputs, and from both (the history a robot out of room B needs at C's doorways); the classes' step counts
    are printed, and a score is "—" when either class has fewer than 20 steps in either half;
  - how often the greedy robot switches behaviour between consecutive steps of a trial.

    python scripts/ch8/context_probe.py [--seeds 100:103] [--tests 10] [--set lessons_per_trial=100 ...]
"""

from __future__ import annotations

import argparse

import numpy as np

from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, ROOMS, sample_in_room
from connrl.experiments.integration import EXPERIMENTS, IntegrationParams
from connrl.experiments.recharge import run_rooms
from connrl.experiments.spec import override
from connrl.experiments.sweep import parse_assignment, parse_seeds
from connrl.report.integration import RECURRENT
from connrl.tasks.integration import make_integration_agent, make_integration_env

MIN_CLASS = 20  # steps of each class in each half for a classifier score


def play(env, agent, start, seed, trial: int) -> list[tuple]:
    """One greedy test: per step (trial, context, inputs, previous behaviour or -1, room, came into C through B)."""
    obs, info = env.reset(seed=seed, options={"start": start})
    agent.begin_trial(obs, info, trial=0, learning=False)
    rows, prev, room, from_b = [], -1, info["room"], False
    while True:
        if info["room"] != room:
            from_b, room = info["room"] == "C" and room == "B", info["room"]
        context = agent.net.context.copy()
        b = agent.act(obs, info, greedy=True)
        rows.append((trial, context, np.asarray(obs, dtype=float), prev, ROOMS.index(room), from_b))
        prev = b
        obs, _, terminated, truncated, info = env.step(b)
        if terminated or truncated:
            agent.end_trial()
            return rows


def _design(x: np.ndarray) -> np.ndarray:
    return np.hstack([x, np.ones((len(x), 1))])


def r2(features: np.ndarray, target: np.ndarray, fit: np.ndarray) -> float:
    """Held-out R^2 of a least-squares readout (with bias) of ``target`` from ``features``."""
    w, *_ = np.linalg.lstsq(_design(features[fit]), target[fit], rcond=None)
    err = target[~fit] - _design(features[~fit]) @ w
    return 1.0 - float((err ** 2).sum() / ((target[~fit] - target[fit].mean(0)) ** 2).sum())


def accuracy(features: np.ndarray, label: np.ndarray, fit: np.ndarray) -> float | None:
    """Held-out accuracy of a least-squares linear classifier (+1 / -1, balanced by class weights); None when a class
    is too rare in either half."""
    if min(label[fit].sum(), (~label[fit]).sum(), label[~fit].sum(), (~label[~fit]).sum()) < MIN_CLASS:
        return None
    y = np.where(label, 1.0, -1.0)
    weight = np.where(label[fit], 0.5 / label[fit].mean(), 0.5 / (~label[fit]).mean())
    x = _design(features[fit]) * np.sqrt(weight)[:, None]
    w, *_ = np.linalg.lstsq(x, y[fit] * np.sqrt(weight), rcond=None)
    pred = _design(features[~fit]) @ w > 0
    return float(0.5 * ((pred & label[~fit]).sum() / label[~fit].sum()
                        + (~pred & ~label[~fit]).sum() / (~label[~fit]).sum()))  # balanced accuracy


def _f(v) -> str:
    return "—" if v is None else f"{v:.2f}"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", default="100:103")
    ap.add_argument("--tests", type=int, default=10, help="greedy tests per start room")
    ap.add_argument("--set", nargs="*", default=[], help="IntegrationParams overrides, key=value (JSON values)")
    args = ap.parse_args()
    try:
        lo, hi = parse_seeds(args.seeds)
        if args.tests < 2:
            raise ValueError(f"--tests must be >= 2 (half the tests fit, half score), got {args.tests}")
        spec = EXPERIMENTS[0]
        exp2 = next(v for v in spec.variants if v.label == RECURRENT)
        over = dict(parse_assignment(s) for s in args.set)
        p = override(override(spec.params, exp2.params, "Exp. 2"), over, "--set")
        if p.memory != "recurrent" or p.context < 1:
            raise ValueError("the probe reads the recurrent nets' context: memory must be 'recurrent', context >= 1")
    except ValueError as exc:
        raise SystemExit(f"context_probe: {exc}") from None
    assert isinstance(p, IntegrationParams)
    print(f"recurrent-Q, no X-Y: {over or 'Exp. 2 as the experiment runs it'}; {args.tests} greedy tests per room")
    print("seed | R2 previous behaviour | R2 room | room C steps (came through B) | came through B from: context "
          "| inputs | both | switches per step")
    for seed in range(lo, hi):
        rng = np.random.default_rng(seed)
        _, agent = run_rooms(p, rng, make_integration_env, make_integration_agent)
        env = make_integration_env(p)
        rows, trial = [], 0
        for room in ROOMS:
            for _ in range(args.tests):
                rows += play(env, agent, sample_in_room(rng, env.world.layout, room), int(rng.integers(2**31)), trial)
                trial += 1
        trials = np.array([r[0] for r in rows])
        fit = np.isin(trials, rng.permutation(trial)[: trial // 2])  # split by trial: steps of one trial are alike
        ctx, inputs = np.array([r[1] for r in rows]), np.array([r[2] for r in rows])
        prev = np.array([r[3] for r in rows])
        room = np.eye(len(ROOMS))[[r[4] for r in rows]]
        from_b = np.array([r[5] for r in rows])
        has_prev = prev >= 0
        prev_1hot = np.eye(len(BEHAVIOUR_TASKS))[prev[has_prev]]
        in_c = room[:, ROOMS.index("C")] == 1
        decode = [accuracy(x[in_c], from_b[in_c], fit[in_c]) for x in (ctx, inputs, np.hstack([ctx, inputs]))]
        pairs = (trials[1:] == trials[:-1]) & (prev[:-1] >= 0)  # consecutive choices within one trial
        switches = float(np.mean(prev[1:][pairs] != prev[:-1][pairs]))
        print(f"{seed} | {r2(prev_1hot, ctx[has_prev], fit[has_prev]):.2f} | {r2(room, ctx, fit):.2f} | "
              f"{in_c.sum()} ({from_b[in_c].sum()}) | " + " | ".join(map(_f, decode)) + f" | {switches:.2f}")


if __name__ == "__main__":
    main()
