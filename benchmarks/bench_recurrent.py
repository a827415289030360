"""Time the recurrent OAON hot paths: one BPTT pass (gradient + momentum step) and one forward replay.

Experiments replay the latest 70 trials after every trial (7.5), each a batch BPTT pass, so the per-pass cost
on a 30-step trial (cup task timeout) sets the replay cost; 300 steps shows the per-step cost on long trials.
Sizes are Table B.1's Task 1 recurrent Q-net (I=4, C=8, H=14, 3 actions, 1 output) and recurrent action
model (C=16, H=24, outputs = 4 sensation bits + payoff).

    python benchmarks/bench_recurrent.py
"""

from __future__ import annotations

import time

import numpy as np

from connrl.nets.recurrent import RecurrentNetConfig, RecurrentOAON


def bench(fn, min_time=0.05, repeats=5):
    """Best-of-``repeats`` seconds per call (the minimum is the least disturbed by other processes)."""
    fn()  # compile / warm up
    n = 1
    while True:
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        if time.perf_counter() - t0 >= min_time:
            break
        n *= 2
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        best = min(best, (time.perf_counter() - t0) / n)
    return best


def main():
    rng = np.random.default_rng(0)
    nets = {
        "recurrent-Q (C=8, H=14, O=1)": RecurrentNetConfig(n_inputs=4, n_hidden=14, n_context=8),
        "recurrent-Q shared output": RecurrentNetConfig(n_inputs=4, n_hidden=14, n_context=8,
                                                        share_output=True),
        "recurrent model (C=16, H=24, O=5)": RecurrentNetConfig(n_inputs=4, n_hidden=24, n_context=16,
                                                                n_outputs=5, lr=0.02),
    }
    print(f"{'net':36s} {'T':>4s} {'train_sequence':>15s} {'forward_sequence':>17s} {'per step':>9s}")
    for name, cfg in nets.items():
        net = RecurrentOAON(cfg, n_nets=3, rng=rng)
        for n_t in (30, 300):
            xs = rng.choice([-0.5, 0.5], size=(n_t, cfg.n_inputs))
            actions = rng.integers(0, 3, n_t)
            targets = rng.uniform(-0.5, 0.5, (n_t, cfg.n_outputs))
            t_train = bench(lambda n=net, xs=xs, a=actions, y=targets: n.train_sequence(xs, a, y))
            t_fwd = bench(lambda n=net, xs=xs, a=actions: n.forward_sequence(xs, a))
            print(f"{name:36s} {n_t:4d} {t_train * 1e6:12.1f} us {t_fwd * 1e6:14.1f} us"
                  f" {t_train / n_t * 1e6:6.2f} us")
    net = RecurrentOAON(nets["recurrent-Q (C=8, H=14, O=1)"], n_nets=3, rng=rng)
    x = np.array([0.5, -0.5, -0.5, -0.5])

    def online():
        net.values(x)
        net.advance(1)

    print(f"online values()+advance(): {bench(online) * 1e6:.2f} us per step")
    xs = rng.choice([-0.5, 0.5], size=(30, 4))
    actions = rng.integers(0, 3, 30)
    targets = rng.uniform(0, 1, 30)

    def replay70():
        for _ in range(70):
            net.forward_sequence(xs, actions)
            net.train_sequence(xs, actions, targets)

    print(f"replay of 70 trials x 30 steps (forward + BPTT each): {bench(replay70) * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
