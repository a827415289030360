"""How wide each input reaches the nets: per observation unit, the task's bounds, the spread (standard deviation) of a
random policy's warm-up observations, and that spread after each ``input_scale`` code (connrl.own.spaces).

    python scripts/own_task/input_spread.py --task LunarLander-v3 [--seeds 100 101 102 103 104]

The warm-up is make_agent's own: ``warmup_steps`` (1,000) random-policy steps from the generator make_agent draws for
the seed, so these are the observations that set the scales of the runs on those seeds.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

from connrl.own.options import AgentOptions
from connrl.own.scaling import InputScaler, warmup
from connrl.own.spaces import INPUT_SCALES


def spreads(task: str, seed: int) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The warm-up's raw standard deviation per unit, and per ``input_scale`` that of its encoded observations."""
    env = gym.make(task)
    rng = np.random.default_rng(seed)  # as make_agent draws the warm-up's generator
    seen, _, _ = warmup(env, AgentOptions().warmup_steps, np.random.default_rng(rng.integers(2**63)))
    raw = np.array(seen, dtype=float).reshape(len(seen), -1)
    coded = {by: np.array([InputScaler.fit(env.observation_space, seen, by).encode(x) for x in seen]).std(axis=0)
             for by in INPUT_SCALES}
    return raw.std(axis=0), coded


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", required=True)
    ap.add_argument("--seeds", nargs="+", type=int, default=[100, 101, 102, 103, 104])
    args = ap.parse_args()
    try:
        space = gym.make(args.task).observation_space
    except Exception as exc:  # noqa: BLE001  (an unknown id or a missing extra: one line)
        ap.error(f"cannot make {args.task!r}: {exc}")
    if not isinstance(space, gym.spaces.Box):
        ap.error(f"{args.task}: a Box observation space is read here, got {space}")
    low, high = space.low.ravel(), space.high.ravel()
    rows = [spreads(args.task, seed) for seed in args.seeds]
    print(f"{args.task}: standard deviation of the warm-up's observations per unit, seeds {args.seeds} (min-max)")
    print(f"{'unit':>4} {'bounds':>17} {'raw':>11} " + " ".join(f"{by:>11}" for by in INPUT_SCALES))
    for i in range(low.size):
        cells = [np.array([r[0][i] for r in rows])] + [np.array([r[1][by][i] for r in rows]) for by in INPUT_SCALES]
        print(f"{i:>4} {f'{low[i]:.3g} .. {high[i]:.3g}':>17} "
              + " ".join(f"{f'{c.min():.3f}-{c.max():.3f}':>11}" for c in cells))


if __name__ == "__main__":
    main()
