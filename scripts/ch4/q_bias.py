"""Are Study 2's Q-values inflated? Q(x, a) of each taken action against the discounted return that followed it.

    python scripts/ch4/q_bias.py [--arms global:1:shared local:1 local:2 global:1:four ...] [--seeds 100 101 102]

Each arm is ``REPRESENTATION:LR_SCALE[:shared|four]`` (``four``: four nets on the global inputs,
``SurvivalAgentParams.symmetry=False``; the local representation always has four). Plain QCON trains for 4.3.1's
300 plays (training plays only, no tests) on the seed's training environments; over the last 100 plays every step
records Q(x, a) of the action taken before its update, and the return r + 0.9 r' + ... of the rest of that play.
Printed per arm, averaged over the seeds: mean Q(x, a), mean return, their mean difference (bias: Q-learning's max
over four independent nets would show as a positive one), mean absolute difference, and the mean Q(x, a) at the
steps that killed or starved the agent (return -1). Development seeds only.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from connrl.core.rollout import run_trial
from connrl.envs.survival import SurvivalEnv, environment_sets
from connrl.tasks.survival import SurvivalAgentParams, make_survival_agent

GAMMA, PLAYS, LAST = 0.9, 300, 100


def arm(text: str) -> tuple[str, float, bool]:
    rep, _, rest = text.partition(":")
    scale, _, nets = rest.partition(":")
    try:
        value = float(scale)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give REPRESENTATION:LR_SCALE[:shared|four]") from None
    nets = nets or ("shared" if rep == "global" else "four")
    if rep not in ("global", "local") or not 0 < value < math.inf or nets not in ("shared", "four") \
            or (rep == "local" and nets == "shared"):
        raise argparse.ArgumentTypeError(f"{text!r}: representation global or local, lr scale a number > 0, nets "
                                         "shared (global only) or four")
    return rep, value, nets == "shared"


def run(rep: str, scale: float, shared: bool, seed: int) -> np.ndarray:
    """Rows (Q(x, a), return, fatal) of the last LAST training plays."""
    rng = np.random.default_rng(seed)
    train, _ = environment_sets(int(rng.integers(2**31 - 1)), PLAYS, 50)
    env = SurvivalEnv(rep)
    env.reset(seed=int(rng.integers(2**31 - 1)))
    agent = make_survival_agent(SurvivalAgentParams("QCON", rep, lr_scale=scale, symmetry=shared or rep == "local",
                                                    plays=PLAYS),
                                env, rng)
    steps: list[tuple[float, float]] = []
    observe = agent.observe

    def recording(a, r, y, terminated, truncated, info=None):
        steps.append((float(agent.q.values(agent._x)[a]), float(r)))
        return observe(a, r, y, terminated, truncated, info)

    agent.observe = recording
    out = []
    for k in range(PLAYS):
        steps.clear()
        stats = run_trial(env, agent, trial=k, learning=True, options={"layout_seed": train[k]})
        if k < PLAYS - LAST:
            continue
        g, rows = 0.0, []
        for q, r in reversed(steps):
            g = r + GAMMA * g
            rows.append((q, g, float(r < 0)))
        if stats.truncated:
            raise RuntimeError("a training play was cut short: its return would not be the play's")
        out += rows[::-1]
    return np.array(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", nargs="+", type=arm, default=[("global", 1.0, True), ("global", 1.0, False),
                                                           ("local", 1.0, False), ("local", 2.0, False)])
    ap.add_argument("--seeds", nargs="+", type=int, default=[100, 101, 102])
    args = ap.parse_args()
    if min(args.seeds) < 0:
        ap.error(f"--seeds must be 0 or more, got {min(args.seeds)}")
    print(f"QCON, last {LAST} of {PLAYS} training plays, seeds {' '.join(map(str, args.seeds))}; "
          "means over every step of those plays")
    for rep, scale, shared in args.arms:
        per = [run(rep, scale, shared, s) for s in args.seeds]
        rows = np.concatenate(per)
        fatal = rows[:, 2] > 0
        bias = [float(np.mean(p[:, 0] - p[:, 1])) for p in per]
        nets = "one rotated net" if shared else "four nets"
        print(f"{rep:<6} x{scale:<3g} {nets:<15} Q(x,a) {rows[:, 0].mean():+.3f}"
              f"  return {rows[:, 1].mean():+.3f}  bias {np.mean(bias):+.3f} (per seed "
              f"{' / '.join(f'{b:+.3f}' for b in bias)})  |Q - return| {np.mean(abs(rows[:, 0] - rows[:, 1])):.3f}"
              f"  Q at the fatal step {rows[fatal, 0].mean():+.3f} ({int(fatal.sum())} steps)", flush=True)


if __name__ == "__main__":
    main()
