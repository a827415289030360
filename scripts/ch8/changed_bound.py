"""The fixed rules of ``recharge-bound`` without position in the original and the changed layout (8.4; ours).

The rules' wall followers are fixed per room (WFL in A and B, WFR in C: chosen in the original layout), so this
shows what the same choice of walls does once the doors, the charger and the obstacles have moved. Fresh tasks per
start room (``--tasks``), one generator (``--seed``) for both layouts:

    python scripts/ch8/changed_bound.py [--tasks 40] [--seed 7]
"""

from __future__ import annotations

import argparse

import numpy as np

from connrl.envs.robot.recharge import ROOMS, sample_in_room
from connrl.experiments.recharge_bound import BoundParams, play
from connrl.tasks.recharge import BehaviourEnv, _shipped_library


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--tasks", type=int, default=40, help="fresh tasks per start room and layout")
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    if args.tasks < 1 or args.seed < 0:
        raise SystemExit(f"changed_bound: --tasks must be >= 1 and --seed >= 0, got {args.tasks}, {args.seed}")
    print("layout | rule | docked from A / B / C")
    for layout in ("default", "changed"):
        p0 = BoundParams(position=False)
        env = BehaviourEnv(_shipped_library(), max_steps=p0.max_steps, xy_scale=p0.xy_scale, layout=layout)
        for name, p in (("without position", p0), ("with room history", BoundParams(position=False, history=True))):
            rng = np.random.default_rng(args.seed)
            docked = [np.mean([play(env, p, sample_in_room(rng, env.world.layout, room), int(rng.integers(2**31)))[0]
                               for _ in range(args.tasks)]) for room in ROOMS]
            print(f"{layout} | {name} | " + " / ".join(f"{d:.2f}" for d in docked))


if __name__ == "__main__":
    main()
