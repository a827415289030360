"""Time the Ch. 7 memory agents on the cup task (Table B.1, Task 1; 70 lessons replayed per trial).

Per architecture: the cost of one greedy act() (the test phase's hot path), and of one whole trial of the
experiment (a training trial, the replay after it, and the two greedy test episodes), averaged over
trials 100-150 of a run, when the replay memory is full.

    python benchmarks/bench_memory.py
"""

from __future__ import annotations

import time

import numpy as np

from connrl.core.rollout import run_trial
from connrl.envs.cup import CupCollectionEnv
from connrl.experiments.hidden_state import CupParams
from connrl.tasks.hidden_state import ARCHITECTURES, make_agent, test_score


def main():
    print(f"{'architecture':18} {'act (greedy)':>14} {'trial+replay+test':>19}")
    for arch in ARCHITECTURES:
        p = CupParams(arch=arch)
        rng = np.random.default_rng(0)
        env, test_env = CupCollectionEnv(), CupCollectionEnv()
        env.reset(seed=0)
        test_env.reset(seed=1)
        agent = make_agent(p, 4, 3, rng)
        for k in range(100):  # fill the memory
            run_trial(env, agent, trial=k, learning=True)
        t0 = time.perf_counter()
        for k in range(100, 150):
            run_trial(env, agent, trial=k, learning=True)
            test_score(test_env, agent)
        per_trial = (time.perf_counter() - t0) / 50
        obs, info = test_env.reset(options={"instance": "A"})
        agent.begin_trial(obs, info, learning=False)
        n = 2000
        t0 = time.perf_counter()
        for _ in range(n):
            agent.act(obs, info, greedy=True)
        per_act = (time.perf_counter() - t0) / n
        agent.end_trial()
        print(f"{arch:18} {per_act * 1e6:11.1f} us {per_trial * 1e3:16.1f} ms")


if __name__ == "__main__":
    main()
