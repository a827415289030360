"""Why recurrent-Q's greedy policy on Task 3 (15 % control errors) is not stable at 14 steps: its values at the
decision after the first cup.

    python scripts/ch7/task3_probe.py [--seeds 100 101 102 103 104] [--task 3] [--no-errors] [--trials 500]

Each seed trains recurrent-Q (lambda 0.8, Table B.1) with ``connrl.experiments.hidden_state``'s protocol on the
task; after each of the last 100 training trials the greedy policy is tested from both instances (control errors
off), as the experiment does. In every test the probe reads the Q-values at the step right after the first cup is
picked up: the agent stands on the emptied cell and senses nothing, whether or not its pick-up worked (a failed
pick-up, 15 % in training, has no visible effect). Printed per seed: how often the greedy choice there is "walk on"
(toward the other cup) and "pick up again", the mean of Q(walk on) - Q(pick up) and its share of Q(walk on), how often
that sign flips from one test to the next, and the tests at 14 steps; then where the test episodes first leave the
optimal sequence (at the start, at the first cup, right after it, or on the way to the second, the last pick-up
included), how often they leave it by a pick-up that collects nothing, and, over whole episodes, the extra moves and
pick-ups beyond the optimal 5 and 2 and the share that time out. ``--no-errors`` trains Task 3's learner in a world
without control errors; ``--task 1`` probes Task 1 with its own Table B.1 learner. Development seeds only.
"""

from __future__ import annotations

import argparse

import numpy as np

from connrl.core.rollout import run_trial
from connrl.envs.cup import INSTANCES, CupCollectionEnv
from connrl.experiments.hidden_state import CupParams
from connrl.tasks.hidden_state import CUP_TASKS, OPTIMAL_SCORE, make_agent, make_cup_envs

PICK = 2
TOWARD = {"A": 1, "B": 0}  # after the first cup (cell 3 in A, 7 in B) the other cup lies right in A, left in B


OPTIMAL = {"A": [1, PICK, 1, 1, 1, 1, PICK], "B": [0, PICK, 0, 0, 0, 0, PICK]}
WHERE = ("at the start", "at the first cup", "right after the first cup", "on the way to the second cup")


def first_slip(actions: list[int], instance: str) -> tuple[str, bool] | None:
    """Where a test episode first leaves the optimal sequence, and whether it does so by a pick-up that collects
    nothing (None if it never leaves it)."""
    for t, (a, b) in enumerate(zip(actions, OPTIMAL[instance], strict=False)):
        if a != b:
            return WHERE[min(t, 3)], a == PICK
    return None


def probe_test(env, agent, instance: str) -> tuple[int, np.ndarray | None, list[int]]:
    """One greedy test episode: its steps, the Q-values read right after the first cup (or None), its actions."""
    seen: list[np.ndarray] = []
    values = agent.net.values

    def reading(x):
        q = values(x)
        seen.append(q.copy())
        return q

    agent.net.values = reading
    try:
        obs, info = env.reset(options={"instance": instance})
        agent.begin_trial(obs, info, trial=0, learning=False)
        after_first, steps, done, actions = None, 0, False, []
        while not done:
            actions.append(agent.act(obs, info, greedy=True))
            obs, _, terminated, truncated, info = env.step(actions[-1])
            steps += 1
            done = terminated or truncated
            if after_first is None and len(info["cups"]) == 1:
                after_first = len(seen)  # the next values read are those of the decision after the first cup
        agent.end_trial()
    finally:
        del agent.net.values
    q = seen[after_first] if after_first is not None and after_first < len(seen) else None
    return steps, q, actions


def run(seed: int, task: int, trials: int, errors: bool = True) -> dict:
    p = CupParams(task=task, arch="recurrent-Q", lam=0.8, trials=trials, probe=False)
    rng = np.random.default_rng(seed)
    train_env, test_env = make_cup_envs(task)  # the same draws as run_cup, so a seed trains the same agent
    if not errors:  # the same learner (Table B.1's Task 3 entry) in a training world without control errors
        train_env = CupCollectionEnv(**{**CUP_TASKS[task], "control_error": 0.0})
    train_env.reset(seed=int(rng.integers(2**31)))
    test_env.reset(seed=int(rng.integers(2**31)))
    agent = make_agent(p, train_env.observation_space.shape[0], 3, rng)
    gaps, walks, picks, optimal, slips, extra = {i: [] for i in INSTANCES}, [], [], 0, [], []
    for k in range(trials):
        run_trial(train_env, agent, trial=k, learning=True)
        score = 0
        for inst in INSTANCES:
            steps, q, actions = probe_test(test_env, agent, inst)
            score += steps
            if k >= trials - 100:
                slips.append(first_slip(actions, inst))
                n_pick = sum(a == PICK for a in actions)  # the optimal episode: 5 moves, 2 pick-ups
                extra.append((len(actions) - n_pick - 5, n_pick - 2, steps >= test_env.unwrapped.max_steps))
            if k >= trials - 100 and q is not None:
                walk, pick = q[TOWARD[inst]], q[PICK]
                gaps[inst].append((walk - pick) / abs(walk) if walk else np.nan)
                best = int(np.argmax(q))
                walks.append(best == TOWARD[inst])
                picks.append(best == PICK)
        optimal += k >= trials - 100 and score == OPTIMAL_SCORE
    g = np.concatenate([np.array(v) for v in gaps.values()])
    changes = [np.sign(v[1:]) != np.sign(v[:-1]) for v in map(np.array, gaps.values()) if len(v) > 1]
    flips = np.mean(np.concatenate(changes)) if changes else np.nan  # the same instance, from one test to the next
    moves, pickups, timeouts = np.array(extra, dtype=float).mean(axis=0)
    return {"walk": np.mean(walks), "pick": np.mean(picks), "gap": np.nanmean(g), "gap_sd": np.nanstd(g),
            "flips": flips, "optimal": optimal / min(100, trials), "moves": moves, "pickups": pickups,
            "timeouts": timeouts,
            **{w: float(np.mean([x is not None and x[0] == w for x in slips])) for w in WHERE},
            "by_pickup": float(np.mean([x[1] for x in slips if x is not None])) if any(slips) else float("nan")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", nargs="+", type=int, default=[100, 101, 102, 103, 104])
    ap.add_argument("--task", type=int, choices=[1, 3], default=3)
    ap.add_argument("--no-errors", action="store_true", help="train without control errors, the learner unchanged")
    ap.add_argument("--trials", type=int, default=500)
    args = ap.parse_args()
    if min(args.seeds) < 0 or not 100 <= args.trials <= 100_000:
        ap.error(f"--seeds must be 0 or more and --trials in [100, 100000], got {args.seeds} and {args.trials}")
    print(f"Task {args.task}{' trained without control errors' if args.no_errors else ''}, recurrent-Q lambda 0.8, "
          f"{args.trials} trials; over the last 100 greedy tests, at the "
          "decision after the first cup (both instances):")
    print("seed  greedy: walk on / pick up again   (Q(walk) - Q(pick)) / Q(walk): mean ± SD   sign flips   "
          "tests at 14")
    rows = []
    for seed in args.seeds:
        r = run(seed, args.task, args.trials, errors=not args.no_errors)
        rows.append(r)
        print(f"{seed:>4}  {r['walk']:14.2f} / {r['pick']:.2f}   {r['gap']:+32.3f} ± {r['gap_sd']:.3f}   "
              f"{r['flips']:10.2f}   {r['optimal']:11.2f}", flush=True)
    print("Share of the last 100 tests' episodes (both instances) that first leave the optimal sequence " +
          ", ".join(f"{w}: {np.mean([r[w] for r in rows]):.2f}" for w in WHERE) + " (mean over the seeds); per seed: "
          + "; ".join(" / ".join(f"{r[w]:.2f}" for w in WHERE) for r in rows))
    print("Of those, the share that leave it by a pick-up that collects nothing: " +
          " / ".join(f"{r['by_pickup']:.2f}" for r in rows))
    print("Per episode over the whole episode, extra moves / extra pick-ups / share timed out (30 steps): " +
          "; ".join(f"{r['moves']:.2f} / {r['pickups']:.2f} / {r['timeouts']:.2f}" for r in rows))
    print(f"mean  {np.mean([r['walk'] for r in rows]):14.2f} / {np.mean([r['pick'] for r in rows]):.2f}   "
          f"{np.mean([r['gap'] for r in rows]):+32.3f}           {np.mean([r['flips'] for r in rows]):10.2f}   "
          f"{np.mean([r['optimal'] for r in rows]):11.2f}")


if __name__ == "__main__":
    main()
