"""Why fixing recurrent-model's action model (7.5.2, Task 2) does not keep the optimal policy: what the fixed model's
context units tell the Q-net at the states that need history.

    python scripts/ch7/fixed_model_probe.py [--seeds 100 101 102 103 104] [--freeze-at 300]

Each seed runs ``cup-task2-frozen``'s protocol (recurrent-model, lambda 0.8, Task 2's two random bits) with the
model fixed after ``--freeze-at`` trials, to 500. On the optimal action sequence of each instance (A: right, pick up,
right x4, pick up; B mirrored), played 40 times per instance with fresh random bits and control errors off, four
decisions see no cup and no wall: before the first pick-up (pick up), and the three after it (walk on toward the
other cup: right in A, left in B). There only the context units can tell the right action. At the fixed model and
again at the end (the model is the same; the Q-net has learned on), the probe reports over those 320 states:

- how well the Q-net's inputs (sensation and context) separate the three right actions: the leave-one-out accuracy
  of a nearest-neighbour rule; a least-squares linear rule's accuracy on held-out episodes and in sample, beside
  always guessing the commonest action; and how far apart the classes' centres are against their spread;
- how often the Q-net's greedy action there is the right one, at freezing and over the last 100 trials' tests;
- the share of the last 100 greedy tests at 14 steps (the experiment's measure).

Development seeds only.
"""

from __future__ import annotations

import argparse

import numpy as np

from connrl.core.rollout import run_trial
from connrl.envs.cup import CupCollectionEnv
from connrl.experiments.hidden_state import FrozenModelParams
from connrl.tasks.hidden_state import OPTIMAL_SCORE, make_agent, make_cup_envs, test_score

LEFT, RIGHT, PICK = 0, 1, 2
SCRIPT = {"A": [RIGHT, PICK, RIGHT, RIGHT, RIGHT, RIGHT, PICK], "B": [LEFT, PICK, LEFT, LEFT, LEFT, LEFT, PICK]}
BLIND = (1, 2, 3, 4)  # steps of the script that see neither cup nor wall


def blind_states(agent, rng: np.random.Generator, episodes: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Q-net inputs at the blind steps of the optimal sequences, and the right action at each."""
    env = CupCollectionEnv(random_bits=2, control_error=0.0)
    env.reset(seed=int(rng.integers(2**31)))
    xs, ys = [], []
    for _ in range(episodes):
        for inst, script in SCRIPT.items():
            obs, _ = env.reset(options={"instance": inst})
            agent.model.reset()
            for t, a in enumerate(script):
                x = np.asarray(obs, dtype=np.float64).ravel()
                if t in BLIND:
                    xs.append(agent.q_input(x))
                    ys.append(a)
                agent.model.step(x, a)
                obs, *_ = env.step(a)
    return np.array(xs), np.array(ys)


def separation(xs: np.ndarray, ys: np.ndarray) -> tuple[float, float]:
    """Leave-one-out nearest-neighbour accuracy, and the smallest distance between class centres over the largest
    within-class RMS spread."""
    d = np.linalg.norm(xs[:, None, :] - xs[None, :, :], axis=2)
    np.fill_diagonal(d, np.inf)
    nn = float(np.mean(ys[d.argmin(axis=1)] == ys))
    classes = sorted(set(ys.tolist()))
    centres = {c: xs[ys == c].mean(axis=0) for c in classes}
    spread = max(float(np.sqrt(((xs[ys == c] - centres[c]) ** 2).sum(axis=1).mean())) for c in classes)
    gap = min(float(np.linalg.norm(centres[a] - centres[b])) for a in classes for b in classes if a < b)
    return nn, gap / spread if spread else float("inf")


def linear_accuracy(xs: np.ndarray, ys: np.ndarray, per_episode: int = 8) -> tuple[float, float, float]:
    """A least-squares linear rule (one score per action, bias included): its accuracy fitted on every other episode
    and tested on the rest, then the other way round; in sample; and always guessing the fitted half's commonest
    action on the tested half. Can a rule as simple as a single-layer net read the right action from these inputs?"""
    classes = np.unique(ys)
    xb = np.hstack([xs, np.ones((len(xs), 1))])
    episode = np.arange(len(xs)) // per_episode  # whole episodes to a half, so both halves hold every action
    halves = [episode % 2 == 0, episode % 2 == 1]

    def fit(rows):
        w, *_ = np.linalg.lstsq(xb[rows], (ys[rows, None] == classes[None, :]).astype(float), rcond=None)
        return w

    held, guess = [], []
    for a, b in (halves, halves[::-1]):
        held += list(classes[(xb[b] @ fit(a)).argmax(axis=1)] == ys[b])
        values, counts = np.unique(ys[a], return_counts=True)
        guess += list(ys[b] == values[counts.argmax()])
    inside = float(np.mean(classes[(xb @ fit(slice(None))).argmax(axis=1)] == ys))
    return float(np.mean(held)), inside, float(np.mean(guess))


def greedy_right(agent, xs: np.ndarray, ys: np.ndarray) -> float:
    return float(np.mean([int(np.argmax(agent.q.values(x))) == y for x, y in zip(xs, ys, strict=True)]))


def run(seed: int, freeze_at: int, trials: int = 500) -> dict:
    p = FrozenModelParams(task=2, arch="recurrent-model", lam=0.8, freeze_at=freeze_at, probe=False)
    rng = np.random.default_rng(seed)
    train_env, test_env = make_cup_envs(2)  # the same draws as run_cup, so a seed trains the same agent
    train_env.reset(seed=int(rng.integers(2**31)))
    test_env.reset(seed=int(rng.integers(2**31)))
    agent = make_agent(p, train_env.observation_space.shape[0], 3, rng)
    agent.track_model_error = True  # as run_cup does (it draws nothing, but keeps the protocol the same)
    probe_rng = np.random.default_rng(seed + 10_000)  # the probe's own draws leave the run's untouched
    out, scores, right_late = {}, [], []
    for k in range(trials):
        if k == freeze_at:
            agent.freeze_model = True
            xs, ys = blind_states(agent, probe_rng)
            out["nn"], out["ratio"] = separation(xs, ys)
            out["linear"], out["linear_in"], out["guess"] = linear_accuracy(xs, ys)
            out["right_at_freeze"] = greedy_right(agent, xs, ys)
        run_trial(train_env, agent, trial=k, learning=True)
        scores.append(test_score(test_env, agent))
        if k >= trials - 100 and k >= freeze_at:
            right_late.append(greedy_right(agent, xs, ys))
    out["right_late"] = float(np.mean(right_late)) if right_late else float("nan")
    out["optimal"] = float(np.mean(np.array(scores[-100:]) == OPTIMAL_SCORE))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", nargs="+", type=int, default=[100, 101, 102, 103, 104])
    ap.add_argument("--freeze-at", type=int, default=300)
    args = ap.parse_args()
    if min(args.seeds) < 0 or not 1 <= args.freeze_at <= 400:
        ap.error(f"--seeds must be 0 or more and --freeze-at in [1, 400], got {args.seeds} and {args.freeze_at}")
    print(f"Task 2 recurrent-model, model fixed after {args.freeze_at} of 500 trials; 320 blind states of the optimal "
          "sequences (pick up / walk right / walk left)")
    print("seed  nearest-neighbour   linear rule: held out / in sample / commonest action   centre gap / spread   "
          "greedy right: at fixing / last 100   tests at 14, last 100")
    for seed in args.seeds:
        r = run(seed, args.freeze_at)
        print(f"{seed:>4}  {r['nn']:17.3f}   {r['linear']:24.3f} / {r['linear_in']:.3f} / {r['guess']:.3f}   "
              f"{r['ratio']:19.2f}   {r['right_at_freeze']:21.2f} / {r['right_late']:.2f}   {r['optimal']:21.2f}",
              flush=True)


if __name__ == "__main__":
    main()
