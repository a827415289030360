"""Chapter 7: learning with hidden states. Cup collection (Figs. 7.5, 7.7, 7.8), the robustness probe of
7.5.1, and pole balancing from the cart position and pole angle only (Table 7.1).

Protocol (7.5): each experiment interleaves a learning phase and a test phase. After every training
trial (stochastic actions, one task instance drawn at random) the greedy policy is tested:

- cup tasks: one greedy episode from each instance A and B with control errors off; the score is the sum
  of their steps, each capped by the 30-step timeout (optimal 14, worst 60). 5 runs, 500 trials.
- pole (Task 4): 7 greedy trials from theta = 0, +-1, +-2, +-3 degrees; satisfactory when all balance for
  more than 5000 steps. A run reports the trials until then (None if not within 1000); Table 7.1 is the
  mean of the best 5 of 6 runs, computed in ``results_section``.

Parameters: Table B.1 per task and architecture (``TABLE_B1``); gamma 0.9, initial weights +-0.5,
momentum 0 for perceptrons and 0.9 otherwise (App. B); feedback weight 1.5, BPTT error decay 0.9 (7.4);
replay of the latest 70 trials, the model trained on all past trials (7.5); P_l log-linear in the
lesson's age from 0.01 (latest) to 0.00001 (oldest) for cups, 1e-4 to 1e-7 for the pole (App. B).

Choices where the thesis is silent (R), all in ``CUP_PARAMS`` / ``POLE_PARAMS``:

- Lessons replayed per trial: 70 (as many as the memory holds), drawn from the latest 70 by App. A.2's
  recency rule, for the cup tasks and the pole (as the full-state pole experiment); the action model makes
  as many BPTT passes, on the latest lesson plus uniform draws from all past lessons. With 20 per trial
  window-Q learned Task 1 stably in 11/30 runs against 17/30 with 70 (seeds 100-129, linear output,
  Table B.1's 1/T 10 -> 30).
- The temperature schedule ``1/T: a -> b`` moves linearly over the whole run (500 cup trials, 1000 pole
  trials).
- Window-Q's Q-nets are single-layer perceptrons (H_q = 0) with a *linear* output unit (``linear_perceptron``):
  7.4 gives output units the sigmoid "in the nonlinear case" and calls the linear OAON "single-layer
  perceptrons".
- Deviation from Table B.1: window-Q on the cup tasks anneals ``1/T: 5 -> 30`` (``window_q_inv_t``), the
  schedule Table B.1 gives the other two architectures, instead of its own ``10 -> 30``. Measured with
  ``python scripts/cup_variants.py '{"arch": "window-Q", ...}' 100 130`` (seeds 100-129, not the
  acceptance seeds; 130-159 too for the last), Task 1, lambda 0.8, runs stably optimal over the last 100
  tests: 10 -> 30 sigmoid output 15/30, linear 17/30; 5 -> 30 sigmoid 24/30, linear 58/60.
  With 10 -> 30 the initial Q spread (about +-0.4 sigmoid, +-0.9 linear, from weights in +-0.5 on 39
  inputs) makes the first policy nearly deterministic; failed runs settle into a 19-28-step habit whose
  untried actions keep negative values (e.g. Q = -0.93 for a move worth 0.9^4) and are never explored
  again. The thesis's schedule stays available as the Task 1 variant "window-Q lambda=0.8 1/T 10->30".
- Window-Q and the recurrent-model's feed-forward Q-net also learn on-line from every step (Fig. 3.4);
  recurrent-Q learns only by batch replay.
- The model's payoff output is trained on 0.5 r (the +-0.5 scale of the sensation bits); for the pole its
  outputs span +-1.5 (normalized x and theta reach about +-1.05 at failure).
- Robustness probe (7.5.1): in a trained run whose greedy policy is optimal, for each instance, after the
  first cup is picked up and j = 0..3 further greedy steps, the agent is forced k = 1, 2, 3 steps away from
  the remaining cup; it "resumes optimally" when it then needs exactly distance + 1 steps (walk back and
  pick up). ``robust_fraction`` is the share of the 24 probes resumed optimally.
"""

from __future__ import annotations

import json
from itertools import combinations
from pathlib import Path

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
from connrl.envs.cup import INSTANCES, LEFT, OPTIMAL_STEPS, PICK_UP, RIGHT, CupCollectionEnv
from connrl.envs.pole import PoleBalancingEnv
from connrl.experiments.pole import train_until_satisfactory
from connrl.experiments.protocol import run_trial
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant
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

COMMON = {
    "arch": "recurrent-Q",  # one of ARCHITECTURES (set by the variant)
    "lam": None,  # TD(lambda) recency factor; None = Table B.1 (the lambda = 0 variants set 0)
    "table": {},  # overrides of Table B.1 entries (e.g. {"hq": 12}); empty = the thesis's values
    "gamma": 0.9,  # App. B
    "init_range": 0.5,  # App. B
    "momentum": 0.9,  # App. B: 0.9 for multilayer nets (0 is used for perceptrons)
    "feedback": 1.5,  # constant context feedback weight (7.4)
    "decay": 0.9,  # BPTT error decay on the context path (7.4)
    "share_output": False,  # share hidden->output connections among recurrent action nets (7.4, optional)
    "capacity": 70,  # replay only the latest 70 trials (7.5)
    "online": True,  # feed-forward Q-nets also learn on-line (Fig. 3.4) (R)
    "anneal_trials": None,  # trials of the 1/T schedule; None = the whole run (R)
    "linear_perceptron": True,  # H_q = 0 Q-nets have a linear output unit (7.4: the "linear OAON") (R)
}

CUP_PARAMS = {
    **COMMON,
    "task": 1,  # 1, 2 or 3 (7.5.1-7.5.3)
    "trials": 500,  # 7.5.1: curves over 500 trials
    "lessons_per_trial": 70,  # Q replays per trial from the latest 70, App. A.2 recency (R; 20 was too few)
    "model_lessons_per_trial": 70,  # model BPTT passes per trial over all past trials (R)
    "model_range": 1.0,  # model outputs span +-model_range (R)
    "p_threshold": 0.01,  # P_l for the latest lesson (App. B)
    "p_threshold_oldest": 1e-5,  # P_l for the oldest lesson (App. B)
    "window_q_inv_t": (5.0, 30.0),  # window-Q's 1/T: a -> b; deviation from Table B.1's 10 -> 30 (docstring)
    "probe": True,  # run the robustness probe of 7.5.1 after training
    "probe_steps": [1, 2, 3],  # forced steps in the robustness probe (R: "a few steps")
}

POLE_PARAMS = {
    **COMMON,
    "task": 4,
    "trials": 1000,  # 7.5.4: "not always found within 1000 trials"
    "lessons_per_trial": 70,  # as the full-state pole experiment and the cup tasks (R)
    "model_lessons_per_trial": 70,  # as the cup tasks (R)
    "model_range": 1.5,  # normalized x, theta reach ~1.05 at failure (R)
    "p_threshold": 1e-4,  # App. B
    "p_threshold_oldest": 1e-7,  # App. B
    "train_max_steps": 2000,  # training trials are cut here (truncated, bootstrapped) (R)
    "start_x": 1.2,  # training start ranges (R, as pole-full)
    "start_theta": 0.06,
    "test_steps": 5001,  # "balanced for over 5000 steps" (7.5.4)
}


def table_entry(p: dict) -> dict:
    task, arch = p["task"], p["arch"]
    if task not in TABLE_B1:
        raise ValueError(f"task must be 1, 2, 3 (cups) or 4 (pole), got {task!r}")
    if arch not in TABLE_B1[task]:
        raise ValueError(f"arch must be one of {', '.join(ARCHITECTURES)}, got {arch!r}")
    t = dict(TABLE_B1[task][arch])
    if arch == "window-Q" and p.get("window_q_inv_t") is not None:
        t["inv_t"] = tuple(p["window_q_inv_t"])
    t.update(p.get("table") or {})
    if p.get("lam") is not None:
        t["lam"] = p["lam"]
    return t


def make_agent(p: dict, n_sensation: int, n_actions: int, rng: np.random.Generator):
    """The architecture ``p["arch"]`` with Table B.1's parameters for ``p["task"]`` (plus overrides)."""
    t = table_entry(p)
    arch = p["arch"]
    temp = TemperatureSchedule.inverse(*t["inv_t"], p["anneal_trials"] or p["trials"])
    n = p["lessons_per_trial"]
    replay = ReplayConfig(capacity=p["capacity"], lessons_per_trial=LinearSchedule(n, n),
                          p_threshold=p["p_threshold"], p_threshold_oldest=p["p_threshold_oldest"],
                          batch=arch == "recurrent-Q")
    common = {"init_range": p["init_range"]}
    if arch == "window-Q":
        net = NetConfig(window_input_size(n_sensation, n_actions, t["window"]), t["hq"], value_range=1.0,
                        lr=t["lr_q"], momentum=p["momentum"] if t["hq"] > 0 else 0.0,
                        linear_output=bool(p["linear_perceptron"]) and t["hq"] == 0, **common)
        cfg = QCONConfig(net=net, temperature=temp, gamma=p["gamma"], lam=t["lam"], online=p["online"],
                         replay=replay)
        return WindowQ(cfg, n_actions, rng, n_sensation=n_sensation, window=t["window"])
    rec = {"feedback": p["feedback"], "decay": p["decay"], "momentum": p["momentum"],
           "share_output": p["share_output"], **common}
    if arch == "recurrent-Q":
        net = RecurrentNetConfig(n_sensation, t["hq"], t["cq"], 1, value_range=1.0, lr=t["lr_q"], **rec)
        return RecurrentQ(RecurrentQConfig(net=net, temperature=temp, gamma=p["gamma"], lam=t["lam"],
                                           replay=replay), n_actions, rng)
    model = RecurrentNetConfig(n_sensation, t["hm"], t["cm"], n_sensation + 1, value_range=p["model_range"],
                               lr=t["lr_m"], **rec)
    q_net = NetConfig(n_sensation + t["cm"], t["hq"], value_range=1.0, lr=t["lr_q"],
                      momentum=p["momentum"] if t["hq"] > 0 else 0.0, **common)
    cfg = RecurrentModelConfig(model=model, q_net=q_net, temperature=temp, gamma=p["gamma"], lam=t["lam"],
                               online=p["online"], replay=replay,
                               model_lessons_per_trial=p["model_lessons_per_trial"])
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


def run_cup(p: dict, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    task = CUP_TASKS.get(p["task"])
    if task is None:
        raise ValueError(f"cup task must be 1, 2 or 3, got {p['task']!r}")
    train_env = CupCollectionEnv(**task)
    test_env = WastedPickUps(CupCollectionEnv(random_bits=task["random_bits"], control_error=0.0))  # errors off
    train_env.reset(seed=int(rng.integers(2**31)))
    test_env.reset(seed=int(rng.integers(2**31)))
    agent = make_agent(p, train_env.observation_space.shape[0], 3, rng)
    rows, scores, wasted = [], [], []
    for k in range(p["trials"]):
        stats = run_trial(train_env, agent, trial=k, learning=True)
        test_env.wasted = 0
        score = test_score(test_env, agent)
        scores.append(score)
        wasted.append(test_env.wasted)
        rows.append({"trial": k + 1, "train_steps": stats.steps, "train_done": stats.terminated,
                     "test_steps": score, "test_wasted_pickups": test_env.wasted})
        progress(k + 1, p["trials"])
    scores_a = np.array(scores)
    hit = np.flatnonzero(scores_a == OPTIMAL_SCORE)
    last = scores_a[-min(100, len(scores_a)):]
    metrics = {
        "trials_to_optimal": int(hit[0]) + 1 if hit.size else None,
        "final_steps": float(scores_a[-1]),
        "optimal_last100": float(np.mean(last == OPTIMAL_SCORE)),
        "mean_steps_last100": float(np.mean(last)),
        "wasted_pickups_last100": float(np.mean(wasted[-len(last):])),
        "robust_fraction": None,
    }
    extra = {}
    if p["probe"] and scores_a[-1] == OPTIMAL_SCORE:
        probes = robustness_probe(agent, task["random_bits"], tuple(p["probe_steps"]),
                                  seed=int(rng.integers(2**31)))
        if probes:
            metrics["robust_fraction"] = float(np.mean([r["resumed_optimally"] for r in probes]))
        extra["probes"] = probes
    return RunResult(list(range(1, p["trials"] + 1)), [float(s) for s in scores], metrics, rows, extra)


# ------------------------------------------------------------------------------------------ pole (Task 4)

def run_pole_hidden(p: dict, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    train_env = PoleBalancingEnv(observe="x_theta", max_steps=p["train_max_steps"], start_x=p["start_x"],
                                 start_theta=p["start_theta"])
    test_env = PoleBalancingEnv(observe="x_theta", max_steps=p["test_steps"])
    train_env.reset(seed=int(rng.integers(2**31)))
    agent = make_agent(p, 2, 2, rng)
    return train_until_satisfactory(train_env, test_env, agent, p["trials"], p["test_steps"], progress)


def best_k_mean(values, k: int = 5, fail_value: float | None = None) -> tuple[float | None, int]:
    """Table 7.1's summary: the mean of the best ``k`` runs (lower is better). A run that never reached
    the goal (None) ranks last and, if it is among the best k, counts as ``fail_value`` (a lower bound).
    Returns ``(mean, failures among the best k)``; mean is None when it cannot be formed."""
    vals = sorted(v for v in values if v is not None)
    best = vals[:k]
    n_fail = max(0, min(k, len(values)) - len(best))
    if (n_fail and fail_value is None) or not min(k, len(values)):
        return None, n_fail
    best = best + [fail_value] * n_fail
    return float(np.mean(best)), n_fail


def best5_of_6_distribution(values, fail_value: float) -> tuple[float, float, float]:
    """Table 7.1's best-5-of-6 mean (``best_k_mean``) over every 6-run subset of ``values`` (None counts as
    ``fail_value``): (mean, 5th percentile, 95th percentile)."""
    means = np.array([best_k_mean(c, 5, fail_value)[0] for c in combinations(values, 6)])
    return float(means.mean()), float(np.percentile(means, 5)), float(np.percentile(means, 95))


# ------------------------------------------------------------------------------------------------ specs

def _cup_variants(task: int, lams: tuple[float, ...]) -> tuple[Variant, ...]:
    out = []
    for lam in lams:
        for arch in ARCHITECTURES:
            thesis = {}
            if lam == 0.8 and task == 1:
                thesis = {"final_steps": OPTIMAL_SCORE}  # 7.5.1: all three learned the optimal policy
            out.append(Variant(f"{arch} lambda={lam:g}", {"arch": arch, "lam": lam}, thesis))
    if task == 1:  # Table B.1's own window-Q schedule, beside our deviation (see the module docstring)
        out.insert(1, Variant("window-Q lambda=0.8 1/T 10->30", {"arch": "window-Q", "lam": 0.8,
                                                                  "window_q_inv_t": None}))
    return tuple(out)


_CUP_QUANTITIES = (
    Quantity("final_steps", "test steps for both instances after the last trial (optimal 14)", "lower", "7.5.1"),
    Quantity("trials_to_optimal", "first trial after which the greedy policy takes 14 steps", "lower", "7.5.1"),
    Quantity("optimal_last100", "fraction of the last 100 tests at the optimal 14 steps", "higher", "7.5.2"),
    Quantity("mean_steps_last100", "mean test steps over the last 100 trials", "lower", "7.5"),
    Quantity("wasted_pickups_last100", "pick-ups that collect nothing per test, last 100 tests", "lower", "7.5.3"),
    Quantity("robust_fraction", "share of interruptions after which the agent resumes optimally", "higher",
             "7.5.1"),
)
_CUP_PROFILES = {
    "tiny": {"runs": 1, "trials": 3, "lessons_per_trial": 2, "model_lessons_per_trial": 2},
    "quick": {"runs": 2, "trials": 300},
    "full": {"runs": 5},
}
_TASK_FIGS = {1: ("cup-task1", "Fig. 7.5", "7.5.1", "Task 1: 2-cup collection"),
              2: ("cup-task2", "Fig. 7.7", "7.5.2", "Task 2: Task 1 with two random sensation bits"),
              3: ("cup-task3", "Fig. 7.8", "7.5.3", "Task 3: Task 1 with 15% control errors")}


def _cup_spec(task: int) -> ExperimentSpec:
    name, fig, section, title = _TASK_FIGS[task]
    return ExperimentSpec(
        name=name, title=f"{title} ({fig}): window-Q, recurrent-Q, recurrent-model", section=section,
        run="connrl.experiments.hidden_state:run_cup", params={**CUP_PARAMS, "task": task},
        profiles=_CUP_PROFILES, variants=_cup_variants(task, (0.8, 0.0) if task == 1 else (0.8,)),
        quantities=_CUP_QUANTITIES, x_label="trials",
        y_label="test steps to collect both cups in both instances", y_reference={"optimal": OPTIMAL_SCORE})


_POLE_THESIS = {"window-Q": 206, "recurrent-Q": 552, "recurrent-model": 247}  # Table 7.1

EXPERIMENTS = [
    _cup_spec(1),
    _cup_spec(2),
    _cup_spec(3),
    ExperimentSpec(
        name="cup-robustness",
        title="Robustness probe of 7.5.1: interrupt a trained Task-1 agent, force it the wrong way",
        section="7.5.1", run="connrl.experiments.hidden_state:run_cup", params={**CUP_PARAMS, "task": 1},
        profiles=_CUP_PROFILES,
        variants=tuple(Variant(a, {"arch": a, "lam": 0.8}) for a in ARCHITECTURES),
        quantities=(_CUP_QUANTITIES[5], _CUP_QUANTITIES[0]), x_label="trials",
        y_label="test steps to collect both cups in both instances", y_reference={"optimal": OPTIMAL_SCORE}),
    ExperimentSpec(
        name="pole-hidden", title="Task 4: pole balancing from cart position and pole angle only (Table 7.1)",
        section="7.5.4", run="connrl.experiments.hidden_state:run_pole_hidden", params=POLE_PARAMS,
        profiles={"tiny": {"runs": 1, "trials": 3, "test_steps": 200},
                  "quick": {"runs": 2, "trials": 300},
                  "full": {"runs": 6}},
        variants=tuple(Variant(a, {"arch": a}, {"trials_to_satisfactory": _POLE_THESIS[a]}) for a in ARCHITECTURES),
        quantities=(Quantity("trials_to_satisfactory", "training trials until the greedy policy balances > 5000 "
                             "steps from all 7 test starts", "lower", "Table 7.1"),),
        x_label="training trials", y_label="fraction of runs with a satisfactory policy"),
]


# ---------------------------------------------------------------------------------------------- results

def _fmt(v, digits=1):
    if v is None:
        return "—"
    return f"{v:.{digits}f}" if isinstance(v, float) and not float(v).is_integer() else f"{v:g}"


def _load(out_dir: Path, name: str) -> dict | None:
    p = Path(out_dir) / name / "summary.json"
    return json.loads(p.read_text()) if p.exists() else None


def _cmd(s: dict) -> str:
    return (f"`connrl run {s['experiment']} --profile {s['profile']} --runs {s['runs_per_variant']} "
            f"--seed {s['base_seed']}`")


_TASK_NOTES = {
    1: ["Window-Q uses 1/T 5 -> 30 and a linear output unit (see `connrl/experiments/hidden_state.py`); the "
        "row `1/T 10->30` is Table B.1's own schedule, which leaves many runs in a 15-37-step habit.", "",
        "λ = 0 is clearly worse for window-Q and recurrent-Q, as in the thesis, but only slower for "
        "recurrent-model. A reading: 7.5.1 blames TD(0)'s trouble on states that look alike until the "
        "Q-function has learned features that tell them apart; in recurrent-model those features come from "
        "the action model, which learns them from prediction errors whatever λ is, so the Q-net gets them "
        "without help from the returns (7.6.2's point that the model's training data are directly observed).",
        ""],
    3: ["Why recurrent-Q is not stable at 14 here (the thesis: \"always learned the optimal policy (with little "
        "instability)\"): a failed action has no visible effect and the agent cannot sense the cup in its own "
        "cell, so after a pick-up it does not know whether it holds the cup. Picking up a second time is then "
        "almost as good as walking on: with 15 % errors and gamma 0.9, after the first pick-up in instance A, "
        "walking on is worth about 0.85·0.9^5 + 0.15·0.9^10 = 0.554 and picking up again "
        "0.9·(0.9775·0.9^5 + 0.0225·0.9^10) = 0.526, 5 % apart, less than the 10 % of an ordinary wasted step. "
        "The greedy test policy (errors off) flips between the two, and the extra steps are these pick-ups "
        "(the wasted pick-ups column). Halving the learning rate or replaying 20 instead of 70 lessons per "
        "trial made it worse: mean share of the last 100 tests at 14 0.47 (Table B.1) against 0.21 and 0.01, "
        "8 runs each, `python scripts/cup_variants.py '{\"arch\": \"recurrent-Q\", \"task\": 3}' 100 108` "
        "(add `\"table\": {\"lr_q\": 0.01}` or `\"lessons_per_trial\": 20`).", ""],
}


def results_section(out_dir: Path, doc: Path = Path("docs/RESULTS.md")) -> str:
    """Markdown for docs/RESULTS.md: Ch. 7 numbers beside the thesis's, from OUT/NAME/summary.json."""
    lines = ["## Chapter 7: hidden state (window-Q, recurrent-Q, recurrent-model)", ""]
    found = False
    for task, (name, fig, section, title) in _TASK_FIGS.items():
        s = _load(out_dir, name)
        if s is None:
            continue
        found = True
        lines += [f"### {title} ({fig}, {section})", "",
                  f"Command: {_cmd(s)} (profile `{s['profile']}`, {s['runs_per_variant']} runs per variant, "
                  f"seeds from {s['base_seed']}).", "",
                  "| architecture | runs reaching 14 | first trial at 14 (mean) | steps after last trial "
                  "(per run) | optimal in last 100 tests | mean steps, last 100 | wasted pick-ups per test, "
                  "last 100 | thesis |",
                  "|---|---|---|---|---|---|---|---|"]
        for label, v in s["variants"].items():
            q = v["quantities"]
            tto = q["trials_to_optimal"]
            thesis = {1: "optimal 14 (λ=0.8); λ=0 much worse", 2: "little impact on window-Q and recurrent-Q; "
                      "recurrent-model oscillates", 3: "window-Q optimal in 3/5; recurrent-Q always; "
                      "recurrent-model oscillates"}[task]
            if task == 1 and "lambda=0" in label and "0.8" not in label:
                thesis = "much worse than λ=0.8"
            finals = ", ".join(_fmt(x) for x in q["final_steps"]["per_run"])
            wasted = q.get("wasted_pickups_last100", {}).get("mean")
            lines.append(f"| {label} | {tto['runs_reaching']}/{len(tto['per_run'])} | {_fmt(tto['mean'])} | "
                         f"{finals} | {_fmt(q['optimal_last100']['mean'], 2)} | "
                         f"{_fmt(q['mean_steps_last100']['mean'], 2)} | {_fmt(wasted, 2)} | {thesis} |")
        lines.append("")
        lines += _TASK_NOTES.get(task, [])
    s = _load(out_dir, "cup-robustness") or _load(out_dir, "cup-task1")  # Task 1 runs probe too (lambda=0.8)
    if s is not None:
        found = True
        lines += ["### Robustness probe (7.5.1)", "", f"Command: {_cmd(s)}.", "",
                  "| architecture | share of interruptions resumed optimally (per run; — = policy not optimal) "
                  "| thesis |", "|---|---|---|"]
        thesis = {"window-Q": "not robust (follows its recent actions)",
                  "recurrent-Q": "between the two", "recurrent-model": "robust (acts on the world state)"}
        for label, v in s["variants"].items():
            arch = label.split(" ")[0]
            if label not in (arch, f"{arch} lambda=0.8"):
                continue
            per = ", ".join(_fmt(x, 2) for x in v["quantities"]["robust_fraction"]["per_run"])
            lines.append(f"| {arch} | {per} | {thesis.get(arch, '')} |")
        lines.append("")
    s = _load(out_dir, "pole-hidden")
    if s is not None:
        found = True
        spec = next(e for e in EXPERIMENTS if e.name == "pole-hidden")
        limit = spec.resolve(s["profile"])[0]["trials"]
        n_runs = s["runs_per_variant"]
        lines += ["### Task 4: pole balancing from (x, θ) (Table 7.1)", "", f"Command: {_cmd(s)}.", "",
                  "Table 7.1's measure is the mean of the best 5 of 6 runs; a run without a satisfactory policy "
                  f"within {limit} trials counts as {limit} (marked ≥). With more than 6 runs stored, the "
                  "first 6 (seeds in order) give the protocol's number, and the expected value of that number "
                  "over every 6-run subset of all runs shows how much it depends on which 6 seeds are drawn.",
                  "", "| architecture | trials per run | satisfactory | best 5 of first 6 | best 5 of 6, "
                  f"mean over all 6-subsets of {n_runs} (5-95 %) | thesis | thesis within 5-95 % |",
                  "|---|---|---|---|---|---|---|"]
        for label, v in s["variants"].items():
            q = v["quantities"]["trials_to_satisfactory"]
            runs = q["per_run"]
            mean, n_fail = best_k_mean(runs[:6], 5, fail_value=limit)
            per = ", ".join(_fmt(x) if x is not None else f">{limit}" for x in runs)
            shown = ("≥ " if n_fail else "") + _fmt(mean)
            spread, inside = "—", "—"
            if len(runs) > 6:
                m, lo, hi = best5_of_6_distribution(runs, limit)
                spread = f"{_fmt(m)} ({_fmt(lo)}-{_fmt(hi)})"
                if q["thesis"] is not None:
                    inside = "yes" if lo <= q["thesis"] <= hi else "no"
            ok = sum(x is not None for x in runs)
            lines.append(f"| {label} | {per} | {ok}/{len(runs)} | {shown} | {spread} | {_fmt(q['thesis'])} "
                         f"| {inside} |")
        lines += ["", "When some runs fail, the protocol's number depends strongly on which six seeds are drawn: "
                  "each failure among the best five adds (1000 - its replacement) / 5. The subset spread is the "
                  "fairer comparison with the thesis's single draw.", ""]
    if not found:
        lines += ["No Chapter 7 results stored yet: run `connrl run cup-task1 --profile full` etc.", ""]
    return "\n".join(lines)
