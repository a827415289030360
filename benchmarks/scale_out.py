"""The thesis on more cores: Ray against the process pool on this machine, and the expected time on N cores.

    python benchmarks/scale_out.py --ray --only NAME,... [--profile full] [--workers 2]
    python benchmarks/scale_out.py --from-records /tmp/thesis-full [--cores 2,4,8,16,32,64]

`--ray` runs `connrl reproduce --only ... --quiet` twice into fresh folders, once with the process pool and once with
`--executor ray` (a local Ray instance with --workers CPUs), times both, and checks that every run stored the same
numbers.

`--from-records` reads the run records of a `connrl reproduce` (each run's own time, its compiling included) and
schedules them longest first onto whichever core frees first, on N cores: the expected wall time of the runs on N
cores (the bound below it is the longest run). It orders by the measured times, which the pool only knows as
expectations (connrl/data/run_times.json), and each of N workers compiles once as each of these did: a slight
underestimate. Start-up, the page and Ray's own overhead come on top.
"""

from __future__ import annotations

import argparse
import heapq
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from blocks import paste
from same_numbers import folder_differences

from connrl.experiments.timing import computed


def reproduce(out: Path, only: str, profile: str, workers: int, executor: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "connrl.cli", "reproduce", "--only", only, "--profile", profile, "--out",
                    str(out), "--workers", str(workers), "--executor", executor, "--quiet"], check=True,
                   stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def records(out: Path) -> dict[str, dict]:
    return {str(p.relative_to(out)): json.loads(p.read_text()) for p in Path(out).glob("*/runs/*/*/seed-*.json")}


def makespan(times: list[float], cores: int) -> float:
    """Longest first, each onto the core that frees first (the pool's order)."""
    free = [0.0] * cores
    for t in sorted(times, reverse=True):
        heapq.heappush(free, heapq.heappop(free) + t)
    return max(free)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ray", action="store_true")
    ap.add_argument("--only", default="robot-teaching-dk,robot-dp-copy,recharge-bound,cup-task3,pole-full-ahc")
    ap.add_argument("--profile", default="full")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--from-records", type=Path, default=None)
    ap.add_argument("--cores", default="2,4,8,16,32,64,128")
    ap.add_argument("--write", type=Path, default=None, help="paste the output into this Markdown file's block")
    args = ap.parse_args()
    lines: list[str] = []
    if args.ray:
        base = Path(tempfile.mkdtemp(prefix="scale-out-"))
        wall = {kind: reproduce(base / kind, args.only, args.profile, args.workers, kind)
                for kind in ("process", "ray")}
        moved, both, only_process, only_ray = folder_differences(base / "process", base / "ray")
        same = not moved and not only_process and not only_ray
        lines.append(f"connrl reproduce --only {args.only} --profile {args.profile} --workers {args.workers}: "
                     f"{both} runs; process pool {wall['process']:.1f} s, local Ray {wall['ray']:.1f} s "
                     f"(Ray / process = {wall['ray'] / wall['process']:.2f}); every run's numbers the same: {same}")
    if args.from_records:
        recs = computed(records(args.from_records).values())  # a copied twin run took no time
        times = [float(r["wall_time_s"]) + float(r.get("compile_time_s") or 0.0) for r in recs]
        lines.append(f"{len(times)} runs of {args.from_records}, {sum(times) / 60:.1f} min in all, the longest "
                     f"{max(times):.0f} s; expected wall time of the runs, longest first:")
        lines += [f"  {n:>4} cores: {makespan(times, n) / 60:6.1f} min" for n in map(int, args.cores.split(","))]
    print("\n".join(lines))
    if args.write:
        called = " ".join(["python benchmarks/scale_out.py"] + sys.argv[1:]).split(" --write")[0]
        paste(args.write, "scale_out", called, "\n".join(lines))


if __name__ == "__main__":
    main()
