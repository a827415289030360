"""What Study 2's local representation lets a network policy reach at all: the scripted teacher copied onto nets.

    python scripts/ch4/representation_bound.py [--seeds 100 101 102] [--plays 100] [--rounds 3] [--lr 0.02]

Issue 31 asks to separate the task from the learner. For each representation (global, Study 1; local, Study 2)
and seed, four nets (one per action, 145 inputs, 30 hidden units, the chapter's init and momentum, outputs in +-1)
are fitted to the scripted teacher's choices (``connrl.envs.survival.scripted_teacher_action``, which sees the whole
state) by one-vs-rest regression (``connrl.agents.cloning``: the taught action's net toward +0.5, the others toward
-0.5). Round 0 fits the teacher's own ``--plays`` plays; each further round lets the copy play ``--plays`` plays
greedily, labels the states it visits with the teacher's choice and refits on everything so far (DAgger), so the
copy is trained on the states its own mistakes lead to. Each round ends with the copy's greedy food per play on 50
test environments (``connrl.tasks.survival.environment_sets(seed, 0, 50)``: drawn from the seed itself, so not the
layouts a ``run_survival`` run with that seed tests on).

``global-rotated`` copies onto Study 1's one rotated net instead (4.2.4). The global and local copies get the same
four nets, so a gap between them is the representation's; the teacher's own food on the same tests is the reference.
The copy is a reference for what these inputs support, not a strict bound: a reinforcement learner optimises food and
survival, not agreement with this teacher (docs/RESULTS.md, "Why Study 2 falls short").
Development seeds only.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from connrl.agents.cloning import agreement, copy_epoch
from connrl.envs.survival import ACTION_ROTATION, ROTATION_PERMUTATIONS, SurvivalEnv, scripted_teacher_action
from connrl.nets import OAON, NetConfig
from connrl.nets.rotated import RotatedNet
from connrl.tasks.survival import environment_sets

MARGIN = 0.5  # one-vs-rest targets, a quarter of the outputs' +-1 range's span


def play(env, choose, seed: int, layout: int | None, label: bool):
    """One play from ``choose(obs)``; the visited inputs with the teacher's choice at each (when ``label``)."""
    obs, info = env.reset(seed=seed, options=None if layout is None else {"layout_seed": layout})
    xs, teacher = [], []
    done = False
    while not done:
        if label:
            xs.append(obs)
            teacher.append(scripted_teacher_action(env))
        obs, _, terminated, truncated, info = env.step(choose(obs))
        done = terminated or truncated
    return xs, teacher, info["food_eaten"]


def run(representation: str, seed: int, plays: int, rounds: int, lr: float, epochs: int) -> list[str]:
    rng = np.random.default_rng(seed)
    env = SurvivalEnv(representation.split("-")[0])
    _, tests = environment_sets(seed, 0, 50)
    config = NetConfig(145, 30, value_range=1.0, init_range=0.1, lr=lr, momentum=0.9)
    if representation == "global-rotated":  # Study 1's one net, its inputs rotated per action (4.2.4)
        nets = RotatedNet(config, np.stack([ROTATION_PERMUTATIONS[ACTION_ROTATION[a]] for a in range(4)]), rng)
        nets.n_nets = nets.n_actions  # what connrl.agents.cloning asks of a set of action nets
    else:
        nets = OAON(config, 4, rng)

    def greedy(obs):
        return int(np.argmax(nets.values(obs)))

    def teacher(_obs):
        return scripted_teacher_action(env)

    out = [f"{representation:<6} seed {seed}: teacher's food on the tests "
           f"{np.mean([play(env, teacher, k, k, False)[2] for k in tests]):.2f}"]
    xs, acts = [], []
    for r in range(rounds + 1):
        policy = teacher if r == 0 else greedy
        for _ in range(plays):
            x, a, _ = play(env, policy, int(rng.integers(2**31 - 1)), None, True)
            xs += x
            acts += a
        states, actions = np.array(xs), np.array(acts, dtype=np.int64)
        for _ in range(epochs):
            copy_epoch(nets, states, actions, MARGIN, rng)
        food = np.mean([play(env, greedy, k, k, False)[2] for k in tests])
        out.append(f"  round {r}: {len(states):>6} labelled states, agreement {agreement(nets, states, actions):.3f}, "
                   f"copy's food on the tests {food:.2f}")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", nargs="+", type=int, default=[100, 101, 102])
    ap.add_argument("--plays", type=int, default=100)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--epochs", type=int, default=3)
    ap.add_argument("--lr", type=float, default=0.02)
    ap.add_argument("--representations", nargs="+", choices=["global", "local", "global-rotated"],
                    default=["global", "local"])
    args = ap.parse_args()
    if args.plays < 1 or args.rounds < 0 or args.epochs < 1 or not 0 < args.lr < math.inf or min(args.seeds) < 0:
        ap.error("--plays and --epochs must be 1 or more, --rounds and --seeds 0 or more, --lr a number > 0")
    for rep in args.representations:
        for seed in args.seeds:
            print("\n".join(run(rep, seed, args.plays, args.rounds, args.lr, args.epochs)), flush=True)


if __name__ == "__main__":
    main()
