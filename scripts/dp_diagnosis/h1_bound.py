"""H1 bound: test perf with collision penalties removed, and with repeated collisions removed (steps+reward)."""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import Run

pts = [10, 30, 60, 100]
acc = {k: [] for k in pts}
for seed in range(100, 107):
    r = Run(seed)
    for k in pts:
        r.train(k - r.k)
        tests = r.detailed_test()
        recs = [x for t in tests for x in t["recs"]]
        steps = len(recs)
        tot = sum(x["r"] for x in recs)
        nocoll = sum(x["r"] for x in recs if not x["coll"])
        rep = [x for x in recs if x["coll"] and (x["obs"][48:52] > 0).any()]
        succ = sum(t["success"] for t in tests)
        succ_steps = np.mean([len(t["recs"]) for t in tests if t["success"]]) if succ else np.nan
        acc[k].append(
            (
                tot / steps,
                nocoll / steps,
                (tot + 10 * len(rep)) / (steps - len(rep)),
                succ,
                succ_steps,
                sum(x["coll"] for x in recs),
                len(rep),
            )
        )
for k in pts:
    a = np.array(acc[k], float)
    m = np.nanmean(a, 0)
    print(
        f"trial {k:3d}: perf {m[0]:5.2f}  no-collision-penalty {m[1]:5.2f}  no-repeated-collisions {m[2]:5.2f}  "
        f"successes {m[3]:4.1f}/50 (mean {m[4]:.1f} steps)  collisions {m[5]:.0f} repeated {m[6]:.0f}"
    )
