"""What do the recurrent Q-nets' context units hold? (issue 28, item 2; ours)

Trains Ch. 8's recurrent learner (Exp. 2, no X-Y) on development seeds, then plays greedy tests from every room,
learning off, and fits least-squares readouts of the context c_t (the units every behaviour's net reads at step t)
from three things the robot could remember, each on its own, on held-out steps (half the tests fit, half score):

  - the behaviour chosen at the step before (c_t is made by that behaviour's net, 7.4);
  - the current room (which the inputs show anyway);
  - in room C only: whether the robot came into room C through door B (the history a robot out of room B needs at
    C's doorways).

It prints R^2 of each readout (share of the context's variance it explains) and how often the greedy choice switches
behaviour, per seed:

    python scripts/ch8/context_probe.py [--seeds 100:103] [--set lr=0.02 ...]
"""

from __future__ import annotations

import argparse
import ast

import numpy as np

from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, ROOMS, sample_in_room
from connrl.experiments.integration import RECURRENT, IntegrationParams
from connrl.experiments.recharge import run_rooms
from connrl.tasks.integration import make_integration_agent, make_integration_env


def play(env, agent, start, seed):
    """One greedy test: per step (context, previous behaviour, room, came into C through door B)."""
    obs, info = env.reset(seed=seed, options={"start": start})
    agent.begin_trial(obs, info, trial=0, learning=False)
    rows, prev, room, from_b = [], None, info["room"], False
    while True:
        if info["room"] != room:
            from_b = info["room"] == "C" and room == "B" or (from_b and info["room"] == "C")
            room = info["room"]
        context = agent.net.context.copy()
        b = agent.act(obs, info, greedy=True)
        if prev is not None:
            rows.append((context, prev, ROOMS.index(room), from_b))
        prev = b
        obs, _, terminated, truncated, info = env.step(b)
        if terminated or truncated:
            agent.end_trial()
            return rows


def r2(features: np.ndarray, target: np.ndarray, fit: np.ndarray) -> float:
    """Held-out R^2 of a least-squares readout (with bias) of ``target`` from ``features`` (nan without context)."""
    if target.shape[1] == 0:
        return float("nan")
    x = np.hstack([features, np.ones((len(features), 1))])
    w, *_ = np.linalg.lstsq(x[fit], target[fit], rcond=None)
    err = target[~fit] - x[~fit] @ w
    return 1.0 - float((err ** 2).sum() / ((target[~fit] - target[fit].mean(0)) ** 2).sum())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", default="100:103")
    ap.add_argument("--tests", type=int, default=10, help="greedy tests per start room")
    ap.add_argument("--set", nargs="*", default=[])
    args = ap.parse_args()
    lo, hi = map(int, args.seeds.split(":"))
    over = {k: ast.literal_eval(v) for k, v in (s.split("=", 1) for s in args.set)}
    p = IntegrationParams(**{**RECURRENT, "xy": False, **over})
    print(f"recurrent-Q, no X-Y: {over or 'the experiment settings'}")
    print("seed | R2 previous behaviour | R2 room | R2 came through door B | switches per step")
    for seed in range(lo, hi):
        rng = np.random.default_rng(seed)
        _, agent = run_rooms(p, rng, make_integration_env, make_integration_agent)
        env = make_integration_env(p)
        rows = []
        for room in ROOMS:
            for _ in range(args.tests):
                rows += play(env, agent, sample_in_room(rng, env.world.layout, room), int(rng.integers(2**31)))
        ctx = np.array([r[0] for r in rows])
        prev = np.eye(len(BEHAVIOUR_TASKS))[[r[1] for r in rows]]
        room = np.eye(len(ROOMS))[[r[2] for r in rows]]
        from_b = np.array([[float(r[3])] for r in rows])
        fit = rng.random(len(rows)) < 0.5
        switches = float(np.mean(np.diff([r[1] for r in rows]) != 0))
        in_c = room[:, ROOMS.index("C")] == 1
        print(f"{seed} | {r2(prev, ctx, fit):.2f} | {r2(room, ctx, fit):.2f} | "
              f"{r2(from_b[in_c], ctx[in_c], fit[in_c]):.2f} | "
              f"{switches:.2f}")


if __name__ == "__main__":
    main()
