"""Draw the bound's fixed rule from one room (``connrl.experiments.recharge_bound``): where its primitive steps go.

Plays the rule of ``BoundParams`` (``--set`` a field, e.g. ``wall_C=WFL``) on the first ``--k`` test tasks of a room for
a seed, prints each one's steps and saves a picture of the paths. It shows why the rule needs about 155 steps from
room B: its room-C wall follower, the best single choice for C's own starts, takes a robot that enters C through
door B the long way round C.

    python scripts/ch6/bound_paths.py [--seed 100] [--room B] [--k 4] [--out bound_B.png] [--set wall_C=WFL]
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from connrl.envs.robot import Layout
from connrl.envs.robot.render import render_paths
from connrl.experiments.recharge_bound import BoundParams, fixed_test_tasks, play
from connrl.tasks.recharge import make_recharge_env


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=100)
    ap.add_argument("--room", default="B", choices=("A", "B", "C"))
    ap.add_argument("--k", type=int, default=4)
    ap.add_argument("--out", default="bound_paths.png")
    ap.add_argument("--set", action="append", default=[], help="a BoundParams field, k=v (strings)")
    args = ap.parse_args()
    p = dataclasses.replace(BoundParams(), **dict(kv.split("=", 1) for kv in args.set))
    env = make_recharge_env(p)
    # the test tasks a learning run of this seed is tested on (as run_bound draws them)
    tasks, seeds = fixed_test_tasks(p.tests_per_room, np.random.default_rng(args.seed))
    paths, labels = [], []
    for (room, start), s in zip(tasks, seeds, strict=True):
        if room != args.room or len(paths) == args.k:
            continue
        ok, steps, _ = play(env, p, start, int(s))
        paths.append(list(env.trace))
        labels.append(f"{'docked' if ok else 'not docked'}, {steps} steps")
        print(labels[-1])
    render_paths(Layout.load("default"), paths, labels=labels, title=f"bound rule from room {args.room}",
                 file=args.out)
    print(f"picture: {args.out}")


if __name__ == "__main__":
    main()
