"""README's "What to expect": the two README commands a user runs on a task, for several seeds, through the CLI
exactly as written there (`connrl train ENV --seed S --quiet --save DIR`, then `connrl evaluate DIR [--seed E]`,
10 episodes), with the shipped settings (connrl/data/hyperparams). Prints one line per task and seed set.

    python scripts/own_task/what_to_expect.py [--tasks CartPole-v1 Acrobot-v1 MountainCar-v0] [--out DIR]

Seeds: 0-2 (what the README's commands give), the development seeds 100-104 (the defaults sweep used them) and
the fresh seeds 200-204 (evaluated with --seed 500), CartPole only for the last two sets unless --all-sets.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

SETS = {"0-2": ([0, 1, 2], 0), "development 100-104": (list(range(100, 105)), 0),
        "fresh 200-204": (list(range(200, 205)), 500)}


def one(task: str, seed: int, eval_seed: int, out: Path) -> float:
    folder = out / f"{task}-seed{seed}"
    cmd = [sys.executable, "-m", "connrl.cli"]
    subprocess.run([*cmd, "train", task, "--seed", str(seed), "--quiet", "--save", str(folder)], check=True,
                   stdout=subprocess.DEVNULL)
    text = subprocess.run([*cmd, "evaluate", str(folder), "--seed", str(eval_seed)], check=True, text=True,
                          capture_output=True).stdout
    return float(re.search(r"mean (-?[\d.]+)", text).group(1))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--tasks", nargs="+", default=["CartPole-v1", "Acrobot-v1", "MountainCar-v0"])
    ap.add_argument("--all-sets", action="store_true", help="every seed set on every task")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None, help="where the agents go (default: a temporary folder)")
    args = ap.parse_args()
    out = Path(args.out or tempfile.mkdtemp(prefix="expect-"))
    jobs = [(task, name, seeds, e) for task in args.tasks for name, (seeds, e) in SETS.items()
            if name == "0-2" or args.all_sets or task == "CartPole-v1"]
    with ThreadPoolExecutor(args.workers) as pool:
        results = {(task, name): [pool.submit(one, task, s, e, out) for s in seeds] for task, name, seeds, e in jobs}
        for (task, name), futures in results.items():
            print(f"{task}, seeds {name}: mean greedy return over 10 episodes "
                  + " / ".join(f"{f.result():g}" for f in futures), flush=True)


if __name__ == "__main__":
    main()
