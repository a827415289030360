"""Which wall follower per room should recharge-bound's fixed rule take? All 8 choices on the development seeds.

Each choice plays the recharge-bound rule (connrl.experiments.recharge_bound) on the test tasks of seeds 100-106
(10 per room, as the full profile); printed: the mean share docked per start room and the rule's performance as a
share of the scripted teacher's. The best share of the teacher is recharge-bound's default (docs/RECONSTRUCTION.md,
"Ch. 6 bound").

    python scripts/ch6/bound_walls.py
"""

import itertools

import numpy as np

from connrl.experiments.recharge_bound import WALLS, BoundParams, run_bound

for combo in itertools.product(WALLS, repeat=3):
    p = BoundParams(wall_A=combo[0], wall_B=combo[1], wall_C=combo[2])
    ms = [run_bound(p, np.random.default_rng(s)).metrics for s in range(100, 107)]
    docked = " / ".join(f"{np.mean([m[f'docked_{r}'] for m in ms]):.3f}" for r in "ABC")
    print(f"walls A, B, C = {', '.join(combo)}: docked from A / B / C {docked}; share of the teacher "
          f"{np.mean([m['share_of_teacher'] for m in ms]):.3f}", flush=True)
