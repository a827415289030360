"""Issue 30: why AHCON-R barely learns CartPole-v1 through connrl.own.api, measured.

Trains an agent (AHCON-R by default) on CartPole-v1 and, every ``--every`` steps, logs on a fixed probe set of
states (1,000 states a random policy visits, drawn once): V's mean, the merits' mean and spread (|m1 - m0|), the
share of probe states whose greedy action is 0, the temperature T (raw merit units) and T / spread; over the
window since the last log: the mean episode length, the on-line TD errors (mean and mean |.|) split by the action
taken, each action's share of the actions taken, and replay's used / offered experiences (P_t's skips). At the end
the greedy return (mean of 10 episodes, evaluation seeds 500-509).

    python scripts/own_task/ahcon_cartpole.py [--seeds 0] [--steps 10000] [--kind AHCON-R] [--every 1000]
        [--option p_threshold=0.0 --option lr=0.1 ...] [--quiet]

``--quiet`` prints only each seed's final line (for sweeps). ``--option t_start=0.05 --option t_end=0.005`` gives
AHCON the temperature it had before issue 30 (Q-learning's), under which one action's merit soon dominates every
state (docs/PERFORMANCE.md, "AHCON on your own task").
"""

from __future__ import annotations

import argparse
import ast
import time

import gymnasium as gym
import numpy as np

import connrl
import connrl.agents.ahcon as ahcon_module
from connrl.own.callbacks import Callback


def probe_states(env, n: int = 1000, seed: int = 12345) -> list:
    rng = np.random.default_rng(seed)
    obs, _ = env.reset(seed=seed)
    out = []
    while len(out) < n:
        obs, _, term, trunc, _ = env.step(int(rng.integers(2)))
        out.append(obs)
        if term or trunc:
            obs, _ = env.reset(seed=int(rng.integers(2**31)))
    return out


class Probe(Callback):
    def __init__(self, probes, every: int, quiet: bool):
        self.probes, self.every, self.quiet = probes, every, quiet
        self.next_log, self.lengths = every, []
        self.td = {0: [], 1: []}
        self.replay = [0, 0]  # used, offered

    def on_training_start(self, agent, total_steps):
        learner = agent.learner
        if not self.quiet:
            print("start (after the warm-up, before any learning): " + self.line(agent), flush=True)
        if not agent.kind.startswith("AHCON"):
            return
        update_error = learner.policy.update_error

        def logged(x, a, error):  # on-line (Fig. 3.2 step 6) and replayed updates both pass here
            self.td[int(a)].append(float(error))
            return update_error(x, a, error)

        learner.policy.update_error = logged
        replay = ahcon_module.replay_ahc

        def counted(v, policy, lesson, params):
            used = replay(v, policy, lesson, params)
            self.replay[0] += used
            self.replay[1] += len(lesson)
            return used

        ahcon_module.replay_ahc = counted
        self._restore = lambda: setattr(ahcon_module, "replay_ahc", replay)

    def on_training_end(self, agent):
        if hasattr(self, "_restore"):
            self._restore()

    def on_trial_end(self, agent, stats):
        self.lengths.append(stats.steps)
        if agent.steps_done >= self.next_log:
            self.next_log += self.every
            if not self.quiet:
                print(self.line(agent), flush=True)

    def line(self, agent) -> str:
        learner = agent.learner
        xs = [agent.scaler.encode(o) for o in self.probes]
        if agent.kind.startswith("AHCON"):
            v = np.array([learner.v.value(x, 0) for x in xs])
            m = np.array([learner.policy.values(x) for x in xs])
        else:
            m = np.array([learner.q.values(x) for x in xs])
            v = m.max(axis=1)
        spread = np.abs(m[:, 1] - m[:, 0])
        t = agent.temperature(agent.trials_done)
        length = np.mean(self.lengths) if self.lengths else 0.0
        s = (f"step {agent.steps_done:>6} trials {agent.trials_done:>5} len {length:6.1f} | "
             f"V {v.mean():7.2f} merits {m[:, 0].mean():7.2f} {m[:, 1].mean():7.2f} spread {spread.mean():6.2f} "
             f"(med {np.median(spread):5.2f}) greedy0 {np.mean(m[:, 0] > m[:, 1]):.2f} T {t:5.2f} "
             f"T/spread {t / max(spread.mean(), 1e-9):6.2f}")
        if agent.kind.startswith("AHCON"):
            n0, n1 = len(self.td[0]), len(self.td[1])
            td = [f"a{a}: n {len(e)} mean {np.mean(e) if e else 0:+.3f} |.| {np.mean(np.abs(e)) if e else 0:.3f}"
                  for a, e in self.td.items()]
            s += (f" | TD {'; '.join(td)} share0 {n0 / max(n0 + n1, 1):.2f} | replay used "
                  f"{self.replay[0]}/{self.replay[1]} ({self.replay[0] / max(self.replay[1], 1):.2f})")
        self.lengths, self.td, self.replay = [], {0: [], 1: []}, [0, 0]
        return s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--steps", type=int, default=10_000)
    ap.add_argument("--kind", default="AHCON-R")
    ap.add_argument("--every", type=int, default=1000)
    ap.add_argument("--option", action="append", default=[], help="an AgentOptions field, name=value")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args()
    options = {}
    for item in args.option:
        name, value = item.split("=", 1)
        options[name] = ast.literal_eval(value)
    env = gym.make("CartPole-v1")
    probes = probe_states(env)
    means = []
    for seed in args.seeds:
        t0 = time.perf_counter()
        agent = connrl.make_agent(env, args.kind, seed=seed, **options)
        probe = Probe(probes, args.every, args.quiet)
        agent.learn(args.steps, callback=probe)
        mean = float(np.mean(connrl.evaluate(agent, env, 10, seed=500)))
        means.append(mean)
        print(f"{args.kind} {options} seed {seed}: {args.steps} steps ({agent.trials_done} trials), greedy return "
              f"{mean:.1f} ({time.perf_counter() - t0:.0f} s)", flush=True)
    if len(args.seeds) > 1:
        print(f"{args.kind} {options} mean over seeds {args.seeds}: {np.mean(means):.1f}  {[round(m) for m in means]}")


if __name__ == "__main__":
    main()
