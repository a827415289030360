"""What does Exp. 3's learner do from rooms B and C? (a diagnosis of Ch. 6's failure from B)

Trains one run (``run_recharge``, dev seed) while logging every step of the learning trials, then plays the final
greedy policy on the run's own fixed test tasks and prints:
  - exploration: mean length of a behaviour's uninterrupted run; how often the persistence rule is broken by a
    behaviour "becoming applicable", and how many of those are flicker (the new behaviour was applicable 2 steps
    before, i.e. a one-step dropout, or it is inapplicable again within 3 steps);
  - greedy tests from B and C: behaviour shares, rooms reached, where the trials end (final room, position, spread of
    the last 50 steps), DP chosen away from doors.
Extra ``--set k=v`` overrides RechargeParams fields.

    python scripts/ch6/diagnose_policy.py [--seed 100] [--trials 150] [--set "target_max='all'"]
"""

from __future__ import annotations

import argparse
import ast
import collections

import numpy as np

import connrl.experiments.recharge as rx
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS
from connrl.experiments.recharge import RechargeParams, run_recharge

DOORS = {"A": (114.0, 300.0), "B": (246.0, 300.0)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=100)
    ap.add_argument("--trials", type=int, default=150)
    ap.add_argument("--set", nargs="*", default=[])
    args = ap.parse_args()
    over = {k: ast.literal_eval(v) for k, v in (s.split("=", 1) for s in args.set)}
    p = RechargeParams(trials=args.trials, **over)
    box = {}
    make_agent = rx.make_high_level_agent

    def capture(params, rng):
        agent = make_agent(params, rng)
        box["agent"] = agent
        log = box.setdefault("log", [])
        act = agent.act

        def logged_act(obs, info=None, *, greedy=False):
            was, active = agent.choice._was_applicable, agent.choice._active
            b = act(obs, info, greedy=greedy)
            if not greedy:
                log.append((agent.learning, np.array(info["applicable"]), None if was is None else was.copy(),
                            active, b, agent.choice._w.copy(), bool(info.get("behaviour_goal", False))))
            return b

        agent.act = logged_act
        return agent

    rx.make_high_level_agent = capture
    res = run_recharge(p, np.random.default_rng(args.seed))
    print("final docked A/B/C", [round(res.metrics[f"final_docked_{r}"], 2) for r in "ABC"],
          "last row", {k: v for k, v in res.rows[-1].items() if k.startswith("docked")})

    # ---- exploration statistics (learning trials)
    log = box["log"]
    runs, cur, prev = [], 0, None
    breaks = flicker_back = flicker_gone = persisted = first = goal_end = inapp_end = 0
    became = collections.Counter()
    for i, (_, app, was, active, b, w, _goal) in enumerate(log):
        if active is None:
            first += 1
            if cur:
                runs.append(cur)
            cur, prev = 1, b
            continue
        cur = cur + 1 if b == prev else (runs.append(cur) or 1)
        prev = b
        if w[active] > 1:
            persisted += 1
            continue
        if not app[active]:
            inapp_end += 1
            continue
        new = app & ~was
        if new.any():
            breaks += 1
            for k in np.flatnonzero(new):
                became[BEHAVIOUR_TASKS[k]] += 1
            k = int(np.flatnonzero(new)[0])
            back = i >= 2 and log[i - 2][3] is not None and log[i - 1][2] is not None and bool(log[i - 1][2][k])
            flicker_back += back
            fut = [log[j][1][k] for j in range(i + 1, min(i + 4, len(log))) if log[j][3] is not None]
            flicker_gone += (len(fut) > 0 and not all(fut))
        else:
            goal_end += 1
    runs.append(cur)
    n = len(log)
    print(f"exploration: {n} steps, mean uninterrupted run {np.mean(runs):.1f} steps (median {np.median(runs):.0f})")
    print(f"  steps with persistence weight on: {persisted / n:.2f}; W back to 0/1 because a behaviour became "
          f"applicable: {breaks / n:.3f} of steps ({breaks}), of these the new one was applicable 2 steps before "
          f"{flicker_back / max(breaks, 1):.2f}, inapplicable again within 3 steps "
          f"{flicker_gone / max(breaks, 1):.2f}; "
          f"active behaviour inapplicable {inapp_end / n:.3f}; goal reached {goal_end / n:.3f}")
    print("  became applicable:", dict(became))
    applic = np.array([e[1] for e in log])
    print("  applicable share DK/DP/WFL/WFR:", applic.mean(0).round(2))
    chosen = collections.Counter(BEHAVIOUR_TASKS[e[4]] for e in log)
    print("  chosen:", {k: round(v / n, 2) for k, v in chosen.items()})

    # ---- greedy tests from B and C with the final policy
    agent = box["agent"]
    env = rx.make_recharge_env(p)
    task_rng = np.random.default_rng(np.random.default_rng(args.seed).integers(2**63))
    tasks = [(r, env.world.sample_start(task_rng, r)) for r in rx.ROOMS for _ in range(p.tests_per_room)]
    seeds = task_rng.integers(2**31, size=len(tasks))
    for room in "BC":
        print(f"--- greedy tests from {room}")
        for (r, start), s in zip(tasks, seeds, strict=True):
            if r != room:
                continue
            obs, info = env.reset(seed=int(s), options={"start": start})
            agent.begin_trial(obs, info, trial=0, learning=False)
            seq, rooms, poses, dp_far = [], [info["room"]], [], 0
            while True:
                b = agent.act(obs, info, greedy=True)
                q = agent.q.values(agent._x)
                obs, rew, term, trunc, info = env.step(b)
                seq.append(BEHAVIOUR_TASKS[b])
                x, y, _ = info["pose"]
                poses.append((x, y))
                if b == 1 and min(np.hypot(x - dx, y - dy) for dx, dy in DOORS.values()) > 60:
                    dp_far += 1
                if info["room"] != rooms[-1]:
                    rooms.append(info["room"])
                if term or trunc:
                    break
            last = np.array(poses[-50:])
            segs = [(k, len(list(g))) for k, g in __import__("itertools").groupby(seq)]
            print(f"start ({start[0]:.0f},{start[1]:.0f}) docked={info['success']} steps={len(seq)} rooms="
                  f"{'>'.join(rooms)} end=({poses[-1][0]:.0f},{poses[-1][1]:.0f}) last50 spread="
                  f"{last.std(0).round(0).tolist()} share {dict(collections.Counter(seq))} DPfar={dp_far} "
                  f"Q_end={np.round(q, 1).tolist()} segs={segs[:12]}{'...' if len(segs) > 12 else ''}")


if __name__ == "__main__":
    main()
