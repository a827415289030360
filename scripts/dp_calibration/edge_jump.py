"""Door-edge threshold from the caption of Fig. 5.3b/c: at L3 (and L4) facing north "four edges are detected
here, but only two of them are real door edges". For each threshold, the share of noisy scans at L3 and L4
(facing north) that show exactly four door-edge bits; the calibrated ``edge_jump`` is the threshold with the
largest share. Deterministic (seed 0); a few seconds. Issue 12's calibration ran it in the SPEC's 36-in doors
(before the door width was chosen) with a body-surface sonar; its 48-in doors give the same answer. Issue 44 applies
the same caption as a filter on every world it searches (``connrl.experiments.world_family.caption_shares``).

    python scripts/dp_calibration/edge_jump.py [--door-width 36] [--scans 1000] [--sonar-origin body|centre]
    # default: the shipped layout's doors (49 in), the body-surface sonar of issue 12
"""

from __future__ import annotations

import argparse
from collections import Counter

import numpy as np

from connrl.envs.robot import Layout, RobotSim


def four_edge_share(layout: Layout, jump: float, scans: int, seed: int = 0,
                    sonar_origin: str = "body") -> tuple[float, float]:
    out = []
    for name in ("L3", "L4"):  # alike by design (Fig. 5.3b/c); both shown so a layout where they differ shows it
        x, y = layout.locations[name][:2]
        sim = RobotSim(layout, np.random.default_rng(seed), edge_jump=jump, sonar_origin=sonar_origin)
        sim.place(x, y, 90.0)  # facing north, as in Fig. 5.3b/c
        counts = Counter(int(sim.sense().door_edge.sum()) for _ in range(scans))
        out.append(counts[4] / scans)
    return out[0], out[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--door-width", type=float, default=None, help="door width in inches (default: the layout's)")
    ap.add_argument("--scans", type=int, default=1000)
    ap.add_argument("--sonar-origin", choices=("body", "centre"), default="body", help="body (default: issue 12's "
                    "calibration, the world before issue 44) or centre (issue 44's world)")
    args = ap.parse_args()
    layout = Layout.load("default")
    if args.door_width is not None:
        layout = layout.with_door_width(args.door_width)
    width = layout.doors["A"].width
    rows = [(jump, *four_edge_share(layout, jump, args.scans, sonar_origin=args.sonar_origin))
            for jump in range(12, 73, 4)]
    print(f"{width:g}-in doors, {args.scans} noisy scans at L3 / L4 facing north")
    print("edge_jump (in) | P(4 edges) at L3 | at L4")
    for jump, a, b in rows:
        print(f"{jump:14d} | {a:16.2f} | {b:.2f}")
    best = max(rows, key=lambda r: r[1] + r[2])
    print(f"calibrated edge_jump: {best[0]} in (largest share of four-edge scans)")


if __name__ == "__main__":
    main()
