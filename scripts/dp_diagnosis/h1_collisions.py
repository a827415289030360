"""H1: collision loops at trial 10 (greedy test), Q of forward when the front bit is on."""

import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import Run

FRONT = 48  # obs index of the front collision bit (DP)
for seed in [100, 101, 102]:
    t0 = time.time()
    r = Run(seed)
    r.train(10)
    tests = r.detailed_test()
    steps = sum(len(t["recs"]) for t in tests)
    tot = sum(x["r"] for t in tests for x in t["recs"])
    coll = [x for t in tests for x in t["recs"] if x["coll"]]
    # repeated collision: a colliding step whose input already had a collision bit on
    rep = [x for x in coll if (x["obs"][48:52] > 0).any()]
    rep_same = [
        x
        for t in tests
        for i, x in enumerate(t["recs"])
        if x["coll"] and i > 0 and t["recs"][i - 1]["coll"] and t["recs"][i - 1]["a"] == x["a"]
    ]
    sides = {}
    for x in coll:
        sides[(x["side"], x["a"])] = sides.get((x["side"], x["a"]), 0) + 1
    frontq = np.array([x["q"] for t in tests for x in t["recs"] if x["obs"][FRONT] > 0])
    nofront = np.array([x["q"] for t in tests for x in t["recs"] if (x["obs"][48:52] < 0).all()])
    succ = sum(t["success"] for t in tests)
    print(
        f"seed {seed}: perf {tot / steps:.2f} succ {succ}/50 steps {steps} collisions {len(coll)} "
        f"of which input had coll bit on {len(rep)}; same-action repeat after collision {len(rep_same)}"
    )
    print("  collisions by (side, action):", dict(sorted(sides.items(), key=lambda kv: -kv[1])))
    if len(frontq):
        print(
            f"  states with FRONT bit on: {len(frontq)}; mean Q per action {np.round(frontq.mean(0), 1)}; "
            f"greedy=forward {np.mean(frontq.argmax(1) == 4):.2f}"
        )
    print(
        f"  states without coll bits: {len(nofront)}; mean Q {np.round(nofront.mean(0), 1)}; "
        f"greedy dist {np.bincount(nofront.argmax(1), minlength=6)}"
    )
    print("  train log", r.train_log, f"{time.time() - t0:.1f}s")
