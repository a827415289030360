"""Ch. 7 wiring (hidden state): the cup-collection world and pole balancing from (x, theta), with the three
memory architectures of Fig. 7.1 built from Table B.1 (``make_agent``), the cup test (``test_score``) and the
robustness probe of 7.5.1.

The builders take ``CupParams`` or ``PoleHiddenParams``, declared here beside them: each parameter once, with its
range and where the thesis states it (``connrl.core.params.param``).

Values marked (R) are reconstructions; docs/RECONSTRUCTION.md, "Cup collection", gives each with its reason.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

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
from connrl.core.params import MAX_UNITS, MAX_WINDOW, check_sequence, check_types, param
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


# the Table B.1 entries ``table`` may override: sizes (window N, hidden and context units) with their bounds
TABLE_SIZES = {"window": (1, MAX_WINDOW), **dict.fromkeys(("hq", "cq", "hm", "cm"), (0, MAX_UNITS))}

TABLE_KEYS = (*TABLE_SIZES, "lam", "lr_q", "lr_m", "inv_t")

PROBE_MAX = 1000  # forced steps of one robustness probe (the probe's world ends a trial at 200 steps)

def _number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)

def check_table(table: dict) -> None:
    """Refuse a ``table`` override that Table B.1 has no entry for, or whose value is out of range: window N and
    the units are whole numbers within TABLE_SIZES, lam in [0, 1], the learning rates > 0, inv_t two 1/T > 0."""
    for key, v in table.items():
        if key in TABLE_SIZES:
            low, high = TABLE_SIZES[key]
            ok, want = isinstance(v, int) and not isinstance(v, bool) and low <= v <= high, f"in [{low}, {high}]"
        elif key == "lam":
            ok, want = _number(v) and 0 <= v <= 1, "in [0, 1]"
        elif key in ("lr_q", "lr_m"):
            ok, want = _number(v) and v > 0, "> 0"
        elif key == "inv_t":
            ok = isinstance(v, (tuple, list)) and len(v) == 2 and all(_number(x) and x > 0 for x in v)
            want = "two numbers > 0 (1/T: a -> b)"
        else:
            raise ValueError(f"parameter table: unknown entry {key!r}; allowed: {', '.join(TABLE_KEYS)}")
        if not ok:
            raise ValueError(f"parameter table entry {key!r} must be {want}, got {v!r}")

def check_hidden_state(p: CupParams | PoleHiddenParams) -> None:
    """The checks the cup and pole parameter classes share beyond ``check_types``: ``table``'s entries and the
    tuples' lengths and values."""
    check_table(p.table)
    if p.probe_steps is not None:
        check_sequence("probe_steps", p.probe_steps, int, 0, PROBE_MAX, 100)
    if p.window_q_inv_t is not None and not (
            len(p.window_q_inv_t) == 2 and all(_number(x) and x > 0 for x in p.window_q_inv_t)):
        raise ValueError(f"parameter window_q_inv_t must be two numbers > 0 (1/T: a -> b), got {p.window_q_inv_t!r}")

@dataclass(frozen=True)
class HiddenStateParams:
    """What the cup tasks and the pole from (x, theta) share; Table B.1 gives each architecture's own values."""

    arch: str = param("recurrent-Q", note="one of ARCHITECTURES (set by the variant)", choices=ARCHITECTURES)
    lam: float | None = param(None, "0..1", "TD(lambda) recency factor; None = Table B.1 (the lambda = 0 variants set "
                              "0)")
    table: dict = field(default_factory=dict)  # overrides of Table B.1 entries (e.g. {"hq": 12}); {} = thesis's
    gamma: float = param(0.9, "0..1", "App. B")
    init_range: float = param(0.5, ">0", "App. B")
    momentum: float = param(0.9, "0..<1", "App. B: 0.9 for multilayer nets (0 is used for perceptrons)")
    feedback: float = param(1.5, ">=0", "constant context feedback weight (7.4)")
    decay: float = param(0.9, "0..1", "BPTT error decay on the context path (7.4)")
    share_output: bool = param(False, note="share hidden->output connections among recurrent action nets (7.4, "
                               "optional)")
    capacity: int = param(70, ">=1", "replay only the latest 70 trials (7.5)")
    online: bool = param(True, note="feed-forward Q-nets also learn on-line (Fig. 3.4) (R)")
    anneal_trials: int | None = param(None, ">=1", "trials of the 1/T schedule; None = the whole run (R)")
    linear_perceptron: bool = param(True, note="H_q = 0 Q-nets have a linear output unit (7.4: the 'linear OAON') (R)")

@dataclass(frozen=True)
class CupParams(HiddenStateParams):
    """Tasks 1-3 of 7.5.1-7.5.3."""

    task: int = param(1, note="1, 2 or 3 (7.5.1-7.5.3)", choices=(1, 2, 3))
    trials: int = param(500, ">=1", "7.5.1: curves over 500 trials")
    lessons_per_trial: int = param(70, ">=0", "Q replays per trial from the latest 70, App. A.2 recency (R; 20 was "
                                   "too few)")
    model_lessons_per_trial: int = param(70, ">=0", "model BPTT passes per trial over all past trials (R)")
    model_range: float = param(1.0, ">0", "model outputs span +-model_range (R)")
    p_threshold: float = param(0.01, "0..<1", "P_l for the latest lesson (App. B)")
    p_threshold_oldest: float = param(1e-5, ">0", "P_l for the oldest lesson (App. B)")
    window_q_inv_t: tuple | None = param((5.0, 30.0), note="window-Q's 1/T: a -> b; deviation from Table B.1 "
                                         "(docstring)")
    probe: bool = param(True, note="run the robustness probe of 7.5.1 after training")
    probe_steps: tuple = param((1, 2, 3), note="forced steps in the robustness probe (R: 'a few steps')")

    def __post_init__(self):
        check_types(self)
        check_hidden_state(self)

@dataclass(frozen=True)
class PoleHiddenParams(HiddenStateParams):
    """Task 4 of 7.5.4: the pole from the cart position and pole angle only."""

    task: int = param(4, choices=(4,))
    trials: int = param(1000, ">=1", "7.5.4: 'not always found within 1000 trials'")
    lessons_per_trial: int = param(70, ">=0", "as the full-state pole experiment and the cup tasks (R)")
    model_lessons_per_trial: int = param(70, ">=0", "as the cup tasks (R)")
    model_range: float = param(1.5, ">0", "normalized x, theta reach ~1.05 at failure (R)")
    p_threshold: float = param(1e-4, "0..<1", "App. B")
    p_threshold_oldest: float = param(1e-7, ">0", "App. B")
    train_max_steps: int = param(2000, ">=1", "training trials are cut here (truncated, bootstrapped) (R)")
    start_x: float = param(1.2, ">=0", "training start ranges (R, as pole-full)")
    start_theta: float = param(0.06, ">=0")
    test_steps: int = param(5001, ">=1", "'balanced for over 5000 steps' (7.5.4)")
    window_q_inv_t: tuple | None = param(None, note="window-Q's 1/T: None, Table B.1's")
    probe_steps: tuple | None = param(None, note="the robustness probe's forced steps: None, no probe (the cup tasks')")

    def __post_init__(self):
        check_types(self)
        check_hidden_state(self)


def table_entry(p: CupParams | PoleHiddenParams) -> dict:
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


def make_agent(p: CupParams | PoleHiddenParams, n_sensation: int, n_actions: int, rng: np.random.Generator):
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
