"""How Exp. 3's thesis-silent learner settings decide room B (issue 27): each setting undone alone, development seeds.

Runs Exp. 3 (``connrl.experiments.recharge.run_recharge``, the persistence rule) for ``--trials`` trials on each seed
and prints, per row, the share of test tasks docked from rooms A / B / C at the last test (10 fixed tasks a room, mean
over seeds) and the greedy policy's reinforcement per step as a share of the scripted teacher's. The rows: the
defaults; each of the four choices of docs/RECONSTRUCTION.md ("High-level learner") undone alone; all four undone
(the settings before issue 27); the X-Y scales around the default; and, as a diagnostic, greedy tests that keep the
active behaviour (``sticky_test``). About 50 s a row on 2 cores at 20 seeds.

    python scripts/ch6/learner_choices.py [--seeds 100:120] [--trials 60] [--at 60] [--rows defaults,xy_scale=1,...]

The temperature's pace (``cool_trials``) only shows in runs longer than it: ``--trials 150 --at 60``.
"""

from __future__ import annotations

import argparse
from multiprocessing import Pool

import numpy as np

import connrl.agents.behaviour_level as bl
from connrl.core.exploration import weighted_boltzmann_probabilities
from connrl.experiments.recharge import RechargeParams, run_recharge

BEFORE = {"xy_scale": 1.0, "output_init": None, "replay_from_start": False, "init_range": 0.1}
ROWS = {"defaults": {}, **{f"{k}={v}": {k: v} for k, v in BEFORE.items()}, "all four undone": BEFORE,
        **{f"xy_scale={s:g}": {"xy_scale": s} for s in (2.0, 4.0, 16.0, 32.0)},
        **{f"sticky_test={t:g}": {"sticky_test": t} for t in (0.5, 2.0)},
        **{f"cool_trials={n}": {"cool_trials": n} for n in (30, 100, 150)}}
# sticky_test=T (a diagnostic, not a setting of the thesis): the greedy tests choose argmax W(b) e^{Q/T} with Exp. 3's
# persistence W (T in Q units; 2 = Eq. 6.6 at the final temperature 0.02), so the active behaviour is kept unless
# another's Q-value is higher by T ln 100


def _sticky(t_test: float) -> None:
    """Greedy tests keep the active behaviour by Eq. 6.6's W at temperature ``t_test`` (this process only)."""
    original = bl.BehaviourChoice.choose

    def choose(self, q, info, t, rng):
        if t != 0 or not self.persistence:
            return original(self, q, info, t, rng)
        w = self.weights(info)
        p = weighted_boltzmann_probabilities(q, w, t_test)
        b = int(np.argmax(p))
        self._active, self._was_applicable, self._w = b, bl._applicable(info), w
        return b, p

    bl.BehaviourChoice.choose = choose


def _one(job) -> list[float]:
    changes, trials, at, seed = job
    changes = dict(changes)
    if "sticky_test" in changes:
        _sticky(changes.pop("sticky_test"))
    if "output_init" in changes and changes["output_init"] is None:  # the nets' default: drawn like the others
        changes["output_init"] = changes.get("init_range", RechargeParams.init_range)
    r = run_recharge(RechargeParams(trials=trials, **changes), np.random.default_rng(seed))
    last = next(row for row in r.rows if row["trials"] >= at) if at else r.rows[-1]
    return [last[f"docked_{x}"] for x in "ABC"] + [last["performance"] / r.metrics["teacher_performance"]]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="100:120", help="development seeds a:b (default 100:120)")
    ap.add_argument("--trials", type=int, default=60)
    ap.add_argument("--at", type=int, default=0, help="read the test at this trial (default: the last)")
    ap.add_argument("--rows", default=",".join(ROWS), help="comma-separated row names (default: all)")
    args = ap.parse_args()
    a, b = map(int, args.seeds.split(":"))
    rows = [r for r in args.rows.split(",") if r]
    unknown = [r for r in rows if r not in ROWS]
    if unknown:
        raise SystemExit(f"learner_choices: unknown rows {unknown}; allowed: {', '.join(ROWS)}")
    print(f"Exp. 3, {args.trials} trials, seeds {a}-{b - 1}: docked share per room at the "
          f"{'test at trial ' + str(args.at) if args.at else 'last test'} (mean over seeds), "
          "reinforcement per step as a share of the teacher's")
    for row in rows:
        with Pool(2) as pool:  # fresh workers per row: a sticky_test row patches its workers
            res = np.array(pool.map(_one, [(ROWS[row], args.trials, args.at, s) for s in range(a, b)]))
        print(f"{row:28s} A {res[:, 0].mean():.2f}  B {res[:, 1].mean():.2f}  C {res[:, 2].mean():.2f}  "
              f"of teacher {res[:, 3].mean():.2f}  (B per seed: {' '.join(f'{x:.1f}' for x in res[:, 1])})")


if __name__ == "__main__":
    main()
