"""Ch. 7 wiring (hidden state): the cup-collection world and pole balancing from (x, theta), with the three
memory architectures of Fig. 7.1 built from Table B.1 (``make_agent``), the cup test (``test_score``) and the
robustness probe of 7.5.1.

Builders take the experiment's parameters (``connrl.experiments.hidden_state.CupParams`` /
``PoleHiddenParams``) by attribute; ``TableParams`` and ``MemoryAgentParams`` state what they read.

Values marked (R) are reconstructions; docs/RECONSTRUCTION.md, "Cup collection", gives each with its reason.
"""

from __future__ import annotations

import functools
from typing import Protocol

import gymnasium as gym
import numpy as np

from connrl.agents.base import LinearSchedule, ReplayConfig
from connrl.agents.memory import (
    RecurrentModelConfig,
    RecurrentModelQ,
    RecurrentQ,
    RecurrentQConfig,
    WindowQ,
    window_input_size,
)
from connrl.agents.qcon import QCONConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.core.lessons import Lesson
from connrl.core.rollout import run_trial
from connrl.envs.cup import INSTANCES, LEFT, OPTIMAL_STEPS, PICK_UP, RIGHT, CupCollectionEnv
from connrl.nets import NetConfig
from connrl.nets.recurrent import RecurrentNetConfig

ARCHITECTURES = ("window-Q", "recurrent-Q", "recurrent-model")
OPTIMAL_SCORE = 2 * OPTIMAL_STEPS  # 14: both instances (7.5.1)

# Table B.1, per task (1-3: cups, 4: pole) and architecture. N window size; hq/cq Q-net hidden/context units;
# hm/cm model hidden/context units; lr_q/lr_m learning rates; inv_t = (a, b) of "1/T: a -> b".
_WQ1 = {"window": 5, "lam": 0.8, "hq": 0, "lr_q": 0.02, "inv_t": (10.0, 30.0)}
_RQ1 = {"lam": 0.8, "cq": 8, "hq": 14, "lr_q": 0.04, "inv_t": (5.0, 30.0)}
TABLE_B1 = {
    1: {"window-Q": _WQ1, "recurrent-Q": _RQ1,
        "recurrent-model": {"lam": 0.8, "cm": 16, "hm": 24, "lr_m": 0.02, "hq": 10, "lr_q": 0.2,
                            "inv_t": (5.0, 30.0)}},
    2: {"window-Q": _WQ1, "recurrent-Q": _RQ1,
        "recurrent-model": {"lam": 0.8, "cm": 18, "hm": 26, "lr_m": 0.02, "hq": 11, "lr_q": 0.2,
                            "inv_t": (5.0, 30.0)}},
    3: {"window-Q": {**_WQ1, "lr_q": 0.01},
        "recurrent-Q": {"lam": 0.8, "cq": 12, "hq": 20, "lr_q": 0.02, "inv_t": (5.0, 30.0)},
        "recurrent-model": {"lam": 0.8, "cm": 20, "hm": 30, "lr_m": 0.02, "hq": 12, "lr_q": 0.1,
                            "inv_t": (5.0, 30.0)}},
    4: {"window-Q": {"window": 1, "lam": 0.7, "hq": 6, "lr_q": 0.25, "inv_t": (20.0, 50.0)},
        "recurrent-Q": {"lam": 0.7, "cq": 2, "hq": 10, "lr_q": 0.02, "inv_t": (20.0, 50.0)},
        "recurrent-model": {"lam": 0.7, "cm": 4, "hm": 6, "lr_m": 0.005, "hq": 6, "lr_q": 0.5,
                            "inv_t": (15.0, 50.0)}},
}
CUP_TASKS = {1: {"random_bits": 0, "control_error": 0.0},  # 7.5.1
             2: {"random_bits": 2, "control_error": 0.0},  # 7.5.2: two random sensation bits
             3: {"random_bits": 0, "control_error": 0.15}}  # 7.5.3: 15% control errors, off in tests


class TableParams(Protocol):
    """What ``table_entry`` reads (read-only, as the frozen parameter dataclasses are)."""

    @property
    def task(self) -> int: ...
    @property
    def arch(self) -> str: ...
    @property
    def window_q_inv_t(self) -> tuple | None: ...  # window-Q's 1/T: a -> b instead of Table B.1's; None: the table's
    @property
    def table(self) -> dict: ...  # overrides of Table B.1 entries
    @property
    def lam(self) -> float | None: ...  # None: Table B.1's


class MemoryAgentParams(TableParams, Protocol):
    """What ``make_agent`` reads."""

    @property
    def trials(self) -> int: ...
    @property
    def anneal_trials(self) -> int | None: ...  # None: ``trials``
    @property
    def lessons_per_trial(self) -> int: ...
    @property
    def capacity(self) -> int: ...
    @property
    def p_threshold(self) -> float: ...
    @property
    def p_threshold_oldest(self) -> float: ...
    @property
    def init_range(self) -> float: ...
    @property
    def momentum(self) -> float: ...
    @property
    def linear_perceptron(self) -> bool: ...
    @property
    def gamma(self) -> float: ...
    @property
    def online(self) -> bool: ...
    @property
    def feedback(self) -> float: ...
    @property
    def decay(self) -> float: ...
    @property
    def share_output(self) -> bool: ...
    @property
    def model_range(self) -> float: ...
    @property
    def model_lessons_per_trial(self) -> int: ...


def table_entry(p: TableParams) -> dict:
    task, arch = p.task, p.arch
    if task not in TABLE_B1:
        raise ValueError(f"task must be 1, 2, 3 (cups) or 4 (pole), got {task!r}")
    if arch not in TABLE_B1[task]:
        raise ValueError(f"arch must be one of {', '.join(ARCHITECTURES)}, got {arch!r}")
    t = dict(TABLE_B1[task][arch])
    if arch == "window-Q" and p.window_q_inv_t is not None:
        t["inv_t"] = tuple(p.window_q_inv_t)
    t.update(p.table or {})
    if p.lam is not None:
        t["lam"] = p.lam
    return t


def make_agent(p: MemoryAgentParams, n_sensation: int, n_actions: int, rng: np.random.Generator):
    """The architecture ``p.arch`` with Table B.1's parameters for ``p.task`` (plus overrides)."""
    t = table_entry(p)
    arch = p.arch
    temp = TemperatureSchedule.inverse(*t["inv_t"], p.anneal_trials or p.trials)
    n = p.lessons_per_trial
    replay = ReplayConfig(capacity=p.capacity, lessons_per_trial=LinearSchedule(n, n),
                          p_threshold=p.p_threshold, p_threshold_oldest=p.p_threshold_oldest,
                          batch=arch == "recurrent-Q")
    common = {"init_range": p.init_range}
    if arch == "window-Q":
        net = NetConfig(window_input_size(n_sensation, n_actions, t["window"]), t["hq"], value_range=1.0,
                        lr=t["lr_q"], momentum=p.momentum if t["hq"] > 0 else 0.0,
                        linear_output=bool(p.linear_perceptron) and t["hq"] == 0, **common)
        cfg = QCONConfig(net=net, temperature=temp, gamma=p.gamma, lam=t["lam"], online=p.online,
                         replay=replay)
        return WindowQ(cfg, n_actions, rng, n_sensation=n_sensation, window=t["window"])
    rec = {"feedback": p.feedback, "decay": p.decay, "momentum": p.momentum,
           "share_output": p.share_output, **common}
    if arch == "recurrent-Q":
        net = RecurrentNetConfig(n_sensation, t["hq"], t["cq"], 1, value_range=1.0, lr=t["lr_q"], **rec)
        return RecurrentQ(RecurrentQConfig(net=net, temperature=temp, gamma=p.gamma, lam=t["lam"],
                                           replay=replay), n_actions, rng)
    model = RecurrentNetConfig(n_sensation, t["hm"], t["cm"], n_sensation + 1, value_range=p.model_range,
                               lr=t["lr_m"], **rec)
    q_net = NetConfig(n_sensation + t["cm"], t["hq"], value_range=1.0, lr=t["lr_q"],
                      momentum=p.momentum if t["hq"] > 0 else 0.0, **common)
    cfg = RecurrentModelConfig(model=model, q_net=q_net, temperature=temp, gamma=p.gamma, lam=t["lam"],
                               online=p.online, replay=replay,
                               model_lessons_per_trial=p.model_lessons_per_trial)
    return RecurrentModelQ(cfg, n_actions, rng)


# ------------------------------------------------------------------------------------------ cup tasks

class WastedPickUps(gym.Wrapper):
    """Counts pick-ups that collect nothing (``wasted``): the extra steps of Task 3's near-optimal policies."""

    def __init__(self, env: CupCollectionEnv):
        super().__init__(env)
        self.wasted = 0

    def step(self, action):
        cups = len(self.env.unwrapped.cups)
        out = self.env.step(action)
        self.wasted += int(action == PICK_UP and len(self.env.unwrapped.cups) == cups)
        return out


def test_score(env: CupCollectionEnv, agent) -> int:
    """7.5.1's measure: steps of one greedy episode per instance, summed (timeouts count max_steps)."""
    return sum(run_trial(env, agent, trial=0, learning=False, options={"instance": i}).steps for i in INSTANCES)


def probe_once(env: CupCollectionEnv, agent, instance: str, walk: int, forced: int) -> dict | None:
    """One interruption (7.5.1): greedy until the first cup is picked up and ``walk`` more steps, then
    ``forced`` steps away from the remaining cup, then greedy again. None if the greedy policy never picks
    up a first cup or finishes before the interruption."""
    obs, info = env.reset(options={"instance": instance})
    agent.begin_trial(obs, info, trial=0, learning=False)
    steps, walked, terminated = 0, None, False
    try:
        while steps < env.max_steps:
            if walked is not None and walked >= walk:
                break
            obs, _, terminated, truncated, info = env.step(agent.act(obs, info, greedy=True))
            steps += 1
            if terminated or truncated:
                return None
            if walked is None and len(info["cups"]) == 1:
                walked = 0
            elif walked is not None:
                walked += 1
        if walked is None:
            return None
        cup = info["cups"][0]
        away = LEFT if cup > info["position"] else RIGHT
        for _ in range(forced):
            obs, _, terminated, truncated, info = env.step(agent.act(obs, info, greedy=True, force=away))
        start, optimal = info["position"], abs(cup - info["position"]) + 1
        after = 0
        while not (terminated or truncated) and after < 30:  # 30 steps: the trial timeout of 7.5.1
            obs, _, terminated, truncated, info = env.step(agent.act(obs, info, greedy=True))
            after += 1
        return {"instance": instance, "walk": walk, "forced": forced, "position": start, "optimal": optimal,
                "steps": after, "finished": bool(terminated), "resumed_optimally": bool(terminated and
                                                                                      after == optimal)}
    finally:
        agent.end_trial()


def robustness_probe(agent, random_bits: int, forced_steps=(1, 2, 3), walks=range(4), seed: int = 0) -> list[dict]:
    """All interruptions of 7.5.1's probe; the env allows as many steps as needed (no timeout counts)."""
    env = CupCollectionEnv(random_bits=random_bits, control_error=0.0, max_steps=200)
    env.reset(seed=seed)
    out = []
    for inst in INSTANCES:
        for j in walks:
            for k in forced_steps:
                r = probe_once(env, agent, inst, j, k)
                if r is not None:
                    out.append(r)
    return out


def make_cup_envs(task: int) -> tuple[CupCollectionEnv, gym.Wrapper]:
    """Task 1-3's training world and its test world (control errors off, wasted pick-ups counted)."""
    spec = CUP_TASKS.get(task)
    if spec is None:
        raise ValueError(f"cup task must be 1, 2 or 3, got {task!r}")
    return CupCollectionEnv(**spec), WastedPickUps(CupCollectionEnv(random_bits=spec["random_bits"],
                                                                     control_error=0.0))


@functools.lru_cache(maxsize=4)
def _probe_walks(task: int, seed: int, walks: int, unseen: int) -> tuple[tuple[Lesson, np.ndarray], ...]:
    """``model_probe``'s random walks (they depend on ``seed`` alone, so a run's probes, and every run's, share them),
    each with the steps whose next sensation shows a cup after ``unseen`` or more steps without one."""
    env = CupCollectionEnv(random_bits=CUP_TASKS[task]["random_bits"])
    rng = np.random.default_rng(seed)
    out = []
    for w in range(walks):
        x, _ = env.reset(seed=int(rng.integers(2**31)), options={"instance": INSTANCES[w % 2]})
        xs, actions, rewards, done = [x], [], [], False
        while not done:
            a = int(rng.integers(3))
            x, r, terminated, truncated, _ = env.step(a)
            xs.append(x)
            actions.append(a)
            rewards.append(r)
            done = terminated or truncated
        lesson = Lesson(np.array(xs), np.array(actions), np.array(rewards), terminated=terminated,
                        truncated=truncated)
        cup = np.array(xs)[:, :2].max(axis=1) > 0  # a cup in sight in x_0 .. x_n
        seen = [t for t in range(unseen - 1, len(actions))  # the prediction of x_{t+1}
                if cup[t + 1] and not cup[t + 1 - unseen:t + 1].any()]
        out.append((lesson, np.array(seen, dtype=np.int64)))
    return tuple(out)


def model_probe(agent, task: int, seed: int, walks: int = 200, unseen: int = 10) -> dict[str, float | None]:
    """7.5.1's imperfect model away from the agent's own path: the recurrent model's errors on random walks.

    ``walks`` episodes of random actions (instances A and B in turn, control errors off, 30 steps at most), drawn
    from ``seed`` alone, so a run's random stream is untouched; the model is not trained on them. Returns the
    share of steps whose next sensation the model gets wrong in some bit, and the share of steps on which a cup
    comes into sight after ``unseen`` or more steps without one ("if the agent had not seen a cup for 10 steps or
    more, the model normally was unable to predict the appearance of the cup") that it gets wrong (None: none).
    """
    wrong_all, wrong_seen = [], []
    for lesson, seen in _probe_walks(task, seed, walks, unseen):
        wrong = agent.wrong_steps(lesson)
        wrong_seen.extend(wrong[seen])
        wrong_all.append(wrong)
    return {"probe_wrong_steps": float(np.concatenate(wrong_all).mean()),
            "probe_cup_after_unseen_wrong": float(np.mean(wrong_seen)) if wrong_seen else None,
            "probe_cup_after_unseen_n": len(wrong_seen)}
