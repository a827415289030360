"""H4: success at trial N by the start's heading error to the door (through direction), seeds 100-106."""

import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import Run

from connrl.envs.robot import wrap_deg

N = int(sys.argv[1])
lessons = int(sys.argv[2])
bins = {"<30": [0, 0, 0], "30-90": [0, 0, 0], ">90": [0, 0, 0]}
first_a = {"<30": np.zeros(6), "30-90": np.zeros(6), ">90": np.zeros(6)}
for seed in range(100, 107):
    r = Run(seed, lessons=lessons)
    r.train(N)
    tests = r.detailed_test()
    lay = r.test_env.layout
    for (x, y, h), t in zip(r.tests, tests, strict=False):
        d = min(lay.doors.values(), key=lambda d: math.hypot(*(d.center - (x, y))))
        ang = math.degrees(math.atan2(d.center[1] - y, d.center[0] - x))
        e = abs(wrap_deg(ang - h))
        b = "<30" if e < 30 else "30-90" if e < 90 else ">90"
        bins[b][0] += 1
        bins[b][1] += t["success"]
        bins[b][2] += sum(x["coll"] for x in t["recs"])
        first_a[b][t["recs"][0]["a"]] += 1
for b, (n, s, c) in bins.items():
    print(
        f"trial {N} lessons {lessons} heading err {b:6s}: tests {n:3d} success {s / n:.2f} "
        f"collisions/test {c / n:.1f} first action dist {(first_a[b] / n).round(2)}"
    )
