"""Run the environment/agent benchmark scripts and paste their output into docs/PERFORMANCE.md (bench_gymnasium.py,
which takes an hour and more, writes its own block: ``--write``).

    python benchmarks/run_all.py --write docs/PERFORMANCE.md

Each script's stdout goes verbatim into the block ``<!-- NAME:begin --> ... <!-- NAME:end -->``, with the
command that produced it, so every number in the document comes from a committed command.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

from blocks import paste

SCRIPTS = ["bench_speedups.py", "bench_survival_env.py", "bench_robot.py", "bench_recurrent.py", "bench_memory.py",
           "bench_survival_agents.py", "bench_robot_agent.py",
           "bench_recharge.py"]  # bench_gymnasium.py writes its own block (--write)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", type=Path, required=True)
    ap.add_argument("--only", nargs="*", default=None, help="script names to run (default: all)")
    args = ap.parse_args()
    here = Path(__file__).parent
    for script in args.only or SCRIPTS:
        out = subprocess.run([sys.executable, str(here / script)], capture_output=True, text=True, check=True).stdout
        paste(args.write, script.removesuffix(".py"), f"python benchmarks/{script}", out)
        print(f"{script}: done", flush=True)


if __name__ == "__main__":
    main()
