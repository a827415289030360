"""Time the hot paths of connrl against references measured in the same run.

    python benchmarks/bench_core.py                 # print the table
    python benchmarks/bench_core.py --write docs/PERFORMANCE.md   # also regenerate the doc's numbers

(a) one per-sample forward + backward + momentum update of a 145-30-1 net (Ch. 4) and of the 4-6-1 pole
    net, against a straightforward NumPy implementation and a NumPy one with preallocated buffers;
(b) one backward TD(lambda) replay (Fig. 5.1a) of a 100-step lesson through 4 OAON Q-nets of 145-30-1;
(c) environment steps per second (pole balancing; other environments have their own benchmarks).
Each line gives the FLOP count and the fraction of this machine's single-core peak, measured with a large
matrix product in the same run (BLAS limited to one thread, as our kernels use one core).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import re  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from connrl.core.lessons import Lesson  # noqa: E402
from connrl.core.replay import ReplayParams, replay_q, replay_q_reference  # noqa: E402
from connrl.envs.pole import PoleBalancingEnv  # noqa: E402
from connrl.nets import OAON, NetConfig  # noqa: E402


def best_time(fn, number: int, repeat: int = 5) -> float:
    """Seconds per call: the best of ``repeat`` batches of ``number`` calls (least disturbed by other load)."""
    fn()
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def peak_flops() -> float:
    n = 1500
    a, b = np.random.default_rng(0).random((n, n)), np.random.default_rng(1).random((n, n))
    t = best_time(lambda: a @ b, 1, 3)
    return 2 * n**3 / t


def update_flops(n_in: int, n_h: int) -> int:
    """Multiply-adds counted as 2 FLOPs: forward 2 per weight; update ~5 per weight (grad, momentum, add)."""
    n_w = n_h * (n_in + 1) + n_h + 1
    return 7 * n_w


class NaiveNumpyNet:
    """Straightforward NumPy per-sample backprop (allocates every call): the reference of (a)."""

    def __init__(self, n_in, n_h, rng):
        self.w1 = rng.uniform(-0.1, 0.1, (n_h, n_in + 1))
        self.w2 = rng.uniform(-0.1, 0.1, n_h + 1)
        self.d1, self.d2 = np.zeros_like(self.w1), np.zeros_like(self.w2)

    def update(self, x, target, lr=0.1, mom=0.9, scale=2.0):
        xb = np.append(x, 1.0)
        h = 1 / (1 + np.exp(-(self.w1 @ xb))) - 0.5
        hb = np.append(h, 1.0)
        y = 1 / (1 + np.exp(-(self.w2 @ hb))) - 0.5
        delta = (target - scale * y) / scale * (0.25 - y * y)
        dh = delta * self.w2[:-1] * (0.25 - h * h)
        self.d2 = lr * delta * hb + mom * self.d2
        self.d1 = lr * np.outer(dh, xb) + mom * self.d1
        self.w2 += self.d2
        self.w1 += self.d1


class BufferedNumpyNet(NaiveNumpyNet):
    """NumPy with preallocated buffers and in-place updates."""

    def __init__(self, n_in, n_h, rng):
        super().__init__(n_in, n_h, rng)
        self.xb, self.hb = np.ones(n_in + 1), np.ones(n_h + 1)
        self.tmp1 = np.empty_like(self.w1)

    def update(self, x, target, lr=0.1, mom=0.9, scale=2.0):
        xb, hb = self.xb, self.hb
        xb[:-1] = x
        s = self.w1 @ xb
        np.negative(s, out=s)
        np.exp(s, out=s)
        s += 1
        np.reciprocal(s, out=s)
        s -= 0.5
        hb[:-1] = s
        y = 1 / (1 + np.exp(-(self.w2 @ hb))) - 0.5
        delta = (target - scale * y) / scale * (0.25 - y * y)
        dh = delta * self.w2[:-1] * (0.25 - s * s)
        self.d2 *= mom
        self.d2 += (lr * delta) * hb
        self.d1 *= mom
        np.outer(dh * lr, xb, out=self.tmp1)
        self.d1 += self.tmp1
        self.w2 += self.d2
        self.w1 += self.d1


def main() -> list[tuple[str, float, str]]:
    rng = np.random.default_rng(0)
    peak = peak_flops()
    rows: list[tuple[str, float, str]] = []

    def add(name, seconds, flops=None, ref=None):
        extra = []
        if flops:
            extra.append(f"{flops} FLOP, {flops / seconds / 1e9:.2f} GFLOP/s = {flops / seconds / peak:.1%} of peak")
        if ref:
            extra.append(f"{ref[1] / seconds:.1f}x faster than {ref[0]}")
        rows.append((name, seconds, "; ".join(extra)))

    for n_in, n_h, label in ((145, 30, "145-30-1 (Ch. 4)"), (4, 6, "4-6-1 (pole)")):
        x = rng.choice([-0.5, 0.5], n_in)
        naive, buffered = NaiveNumpyNet(n_in, n_h, rng), BufferedNumpyNet(n_in, n_h, rng)
        net = OAON(NetConfig(n_in, n_h, lr=0.1, momentum=0.9), 1, rng)
        t_naive = best_time(lambda naive=naive, x=x: naive.update(x, 0.3), 20000)
        t_buf = best_time(lambda buffered=buffered, x=x: buffered.update(x, 0.3), 20000)
        t_ours = best_time(lambda net=net, x=x: net.update(x, 0, 0.3), 50000)
        fl = update_flops(n_in, n_h)
        add(f"update {label}: straightforward NumPy", t_naive, fl)
        add(f"update {label}: NumPy, preallocated, in place", t_buf, fl)
        add(f"update {label}: connrl (Numba kernel)", t_ours, fl, ("straightforward NumPy", t_naive))

    q = OAON(NetConfig(145, 30, lr=0.05, momentum=0.9), 4, rng)
    lesson = Lesson(rng.choice([-0.5, 0.5], (101, 145)), rng.integers(0, 4, 100), np.zeros(100), terminated=True)
    params = ReplayParams(gamma=0.9, lam=0.7, temperature=0.05, p_threshold=0.01)
    t_rep = best_time(lambda: replay_q(q, lesson, params), 20)  # the registered fast path (compiled kernel)
    t_ref = best_time(lambda: replay_q_reference(q, lesson, params), 3)  # Fig. 5.1(a) as a plain Python loop
    # per step: values(x_{t+1}) and values(x_t) for 4 nets (forward only), one update
    fl_rep = 100 * (2 * 4 * 2 * (30 * 146 + 31) + update_flops(145, 30))
    add("backward replay of a 100-step lesson (4 OAON 145-30-1 nets, lam 0.7): reference loop", t_ref, fl_rep)
    add("backward replay of a 100-step lesson (4 OAON 145-30-1 nets, lam 0.7): compiled kernel", t_rep, fl_rep,
        ("the reference loop", t_ref))

    env = PoleBalancingEnv(max_steps=10**9)
    env.reset(seed=0)
    acts = rng.integers(0, 2, 10000)
    i = [0]

    def step():
        _, _, term, _, _ = env.step(int(acts[i[0] % 10000]))
        i[0] += 1
        if term:
            env.reset()

    t_env = best_time(step, 20000)
    # pole_step: 1 sin + 1 cos and 44 other floating-point operations (counted in connrl/envs/pole.py)
    fl_env = 46
    rows.append(("pole balancing env.step", t_env, f"{1 / t_env:,.0f} steps/s; {fl_env} FLOP, "
                 f"{fl_env / t_env / peak:.2%} of peak (Python per-step overhead dominates)"))
    rows.append(("machine peak (1500x1500 matmul, 1 thread)", 2 * 1500**3 / peak, f"{peak / 1e9:.1f} GFLOP/s"))
    return rows


def table(rows) -> str:
    lines = ["| hot path | time per call | notes |", "|---|---|---|"]
    for name, sec, note in rows:
        t = f"{sec * 1e6:.2f} µs" if sec < 1e-3 else f"{sec * 1e3:.2f} ms"
        lines.append(f"| {name} | {t} | {note} |")
    return "\n".join(lines)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", type=Path, help="replace the generated block of this Markdown file")
    args = ap.parse_args()
    text = table(main())
    stamp = (f"Measured {time.strftime('%Y-%m-%d')} by `python benchmarks/bench_core.py --write docs/PERFORMANCE.md` "
             f"on {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
             f"NumPy {np.__version__}.")
    print(stamp)
    print(text)
    if args.write:
        doc = args.write.read_text()
        block = f"<!-- bench_core:begin -->\n{stamp}\n\n{text}\n<!-- bench_core:end -->"
        doc = re.sub(r"<!-- bench_core:begin -->.*?<!-- bench_core:end -->", block, doc, flags=re.S)
        args.write.write_text(doc)
