"""The eight Ch. 4 agents (AHCON, AHCON-R, AHCON-M, AHCON-T, QCON, QCON-R, QCON-M, QCON-T) for the survival task.

A framework is QCON or AHCON plus options, not a class of its own (3.1):

* ``-R``: experience replay after each play (3.5, 4.2.7): n lessons (12 -> 4 over the plays) from the
  latest 100 by App. A.2, non-policy actions (P < P_t; 0.2 AHC, 0.01 Q) not replayed;
* ``-T``: ``-R`` plus the two taught lessons of ``connrl/data/lessons``, each replayed after a play with a
  probability falling 0.5 -> 0.1, with P_t = 0 (4.2.7);
* ``-M``: relaxation planning (Figs. 3.5, 3.6) on the promising actions (P > 2%) with the learned model
  (no planning in the first 10 plays) or the perfect model (the simulator), see ``connrl.core.planning``
  and ``connrl.tasks.survival_models``.

Representations (4.2.3-4.2.4): ``"global"`` uses ONE Q-net (or policy net) whose inputs are rotated for
the four actions (:class:`connrl.nets.rotated.RotatedNet`); ``"local"`` uses one net per action (OAON).
V-nets always have one output. Every net: 145-30-1, momentum 0.9, initial weights in +-0.1, outputs +-1;
V and Q targets above 1 are truncated to 1 (4.2.4). Learning rates and temperatures: Table 4.1 (Study 2
doubles the learning rates). Stuck detection raises T while the agent stays in a small area without eating
(4.2.6; thresholds are ours, :class:`SurvivalExploration`).

Values marked (R) are reconstructions; docs/RECONSTRUCTION.md, "Learners and protocols", gives each with its reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import gymnasium as gym
import numpy as np

from connrl.agents.ahcon import AHCON, AHCONConfig
from connrl.agents.base import Exploration, LinearSchedule, ReplayConfig
from connrl.agents.qcon import QCON, QCONConfig
from connrl.core.exploration import StuckConfig, TemperatureSchedule
from connrl.core.lesson_files import LessonFileError, save_lessons
from connrl.core.lessons import Lesson
from connrl.core.planning import PlanningConfig, RelaxationPlanner
from connrl.core.rollout import run_trial
from connrl.envs.survival import (
    ACTION_ROTATION,
    ROTATION_PERMUTATIONS,
    SurvivalEnv,
    environment_sets,
    scripted_teacher_lesson,
)
from connrl.envs.survival.world import REWARD_FOOD
from connrl.nets import NetConfig
from connrl.nets.rotated import RotatedNet
from connrl.tasks.survival_models import LearnedModelConfig, LearnedSurvivalModel, PerfectSurvivalModel
from connrl.tasks.survival_play import greedy_play  # a test play, compiled where it can be

SURVIVAL_ENV_ID = "connrl/Survival-v0"
LESSON_DIR = Path(__file__).resolve().parent.parent / "data" / "lessons"
FRAMEWORKS = ("AHCON", "AHCON-R", "AHCON-M", "AHCON-T", "QCON", "QCON-R", "QCON-M", "QCON-T")
MODELS = ("learned", "perfect")


@dataclass(frozen=True)
class SurvivalAgentParams:
    """Parameters of a Ch. 4 agent. Defaults: Table 4.1 (Study 1) and 4.2.7; R = our reconstruction."""

    framework: str = "QCON"  # one of FRAMEWORKS (3.1)
    representation: str = "global"  # "global" (Study 1, 4.3.2) or "local" (Study 2, 4.3.3)
    model: str = "learned"  # action model of the -M agents: "learned" or "perfect" (4.2.5)
    lr_scale: float = 1.0  # Study 2 doubles every learning rate (4.3.3)
    hidden: int = 30  # H_v = H_p = H_q = 30 (Table 4.1)
    momentum: float = 0.9  # 4.3.1
    init_range: float = 0.1  # 4.3.1
    gamma: float = 0.9  # 4.3.1
    plays: int = 300  # plays over which T, n and the taught-lesson probability move (4.3.1)
    lessons_start: int = 12  # lessons replayed after a play, 12 -> 4 (4.2.7)
    lessons_end: int = 4
    taught_start: float = 0.5  # probability of replaying each taught lesson, 0.5 -> 0.1 (4.2.7)
    taught_end: float = 0.1
    promising: float = 0.02  # promising actions: P > 2% (4.2.7)
    p_threshold: float | None = None  # P_t of replay; None: 4.2.7's 0.2 for AHC agents, 0.01 for Q-agents
    model_start: int = 10  # no planning in the first 10 plays with a learned model (4.2.5)
    stuck_window: int = 20  # stuck detection: steps looked at (R)
    stuck_radius: float = 1.5  # ... all within this many cells of their mean (R)
    stuck_boost: float = 5.0  # ... multiplies T (R)
    symmetry: bool = True  # global: one Q- or policy net for all four actions by rotating its inputs (4.2.4); False:
    # four, one per action, on the global inputs (not a thesis agent: scripts/ch4/study2_learner.py's diagnostic arm;
    # a -M agent's learned model keeps its one rotated net of each kind)

    def __post_init__(self):
        if self.framework not in FRAMEWORKS:
            raise ValueError(f"framework must be one of {', '.join(FRAMEWORKS)}, got {self.framework!r}")
        if self.representation not in ("global", "local"):
            raise ValueError(f"representation must be 'global' or 'local', got {self.representation!r}")
        if self.model not in MODELS:
            raise ValueError(f"model must be one of {MODELS}, got {self.model!r}")
        if not isinstance(self.symmetry, bool):
            raise ValueError(f"symmetry must be true or false, got {self.symmetry!r}")
        if not self.symmetry and self.representation == "local":
            raise ValueError("symmetry=False is for the global representation (the local one has no shared net)")


# Table 4.1: (eta_v, eta_p) for AHC agents, eta_q for Q agents; the basic agents learn faster because the
# others "adjusted their networks more often" (4.3.2).
TABLE_4_1 = {
    "AHCON": {"lr_v": 0.2, "lr_p": 0.4, "inv_t": (2.0, 10.0)},
    "AHCON-*": {"lr_v": 0.1, "lr_p": 0.2, "inv_t": (2.0, 10.0)},
    "QCON": {"lr_q": 0.3, "inv_t": (20.0, 60.0)},
    "QCON-*": {"lr_q": 0.15, "inv_t": (20.0, 60.0)},
}


def table_4_1(framework: str) -> dict:
    base = framework.split("-")[0]
    return TABLE_4_1[base if framework == base else base + "-*"]


class SurvivalExploration(Exploration):
    """Temperature with the survival task's stuck detection (4.2.6): dead-reckon the positions of the last
    ``window`` steps; when all lie within ``radius`` cells of their mean and no food was eaten meanwhile,
    multiply T by ``boost``. Eating clears the history ("stuck in a small area without getting food")."""

    def __init__(self, schedule, stuck: StuckConfig):
        super().__init__(schedule, None)
        self.stuck = stuck
        self.boosted = 0  # steps with a raised T (this play)
        self._rows: list[float] = []
        self._cols: list[float] = []
        self._food = -1

    def begin(self, trial: int) -> None:
        super().begin(trial)
        self._rows.clear()
        self._cols.clear()
        self._food, self.boosted = -1, 0

    def temperature(self, info) -> float:
        if not info or "position" not in info:
            return self.base
        c = self.stuck
        food = info.get("food_eaten", 0)
        if food != self._food:
            self._rows.clear()
            self._cols.clear()
            self._food = food
        r, col = info["position"]
        self._rows.append(float(r))
        self._cols.append(float(col))
        if len(self._rows) > c.window:
            del self._rows[0], self._cols[0]
        if len(self._rows) < c.window:
            return self.base
        mr, mc = sum(self._rows) / c.window, sum(self._cols) / c.window
        spread = max(math.hypot(a - mr, b - mc) for a, b in zip(self._rows, self._cols, strict=True))
        if spread <= c.radius:
            self.boosted += 1
            return self.base * c.boost
        return self.base


def write_taught_lessons(seed: int = 0) -> list[Path]:
    """Regenerate connrl/data/lessons/survival-{global,local}.json (``connrl make-lessons survival``)."""
    paths = []
    for representation in ("global", "local"):
        path = LESSON_DIR / f"survival-{representation}.json"
        save_lessons(path, make_taught_lessons(representation, 2, seed), env_id=SURVIVAL_ENV_ID,
                     env_kwargs={"action_representation": representation},
                     source=f"connrl.tasks.survival.make_taught_lessons({representation!r}, n_lessons=2, seed={seed})")
        paths.append(path)
    return paths


def taught_lessons(representation: str) -> list:
    """The two shipped taught lessons for a representation (4.3.1), checked against the task."""
    path = LESSON_DIR / f"survival-{representation}.json"
    return load_survival_lessons(path, representation)


def load_survival_lessons(path, representation: str) -> list:
    """Load a survival lesson file; a file for another task or representation raises LessonFileError."""
    from connrl.core.lesson_files import load_lessons_and_options

    lessons, options = load_lessons_and_options(path, env_id=SURVIVAL_ENV_ID, input_dim=145, n_actions=4)
    recorded = options.get("action_representation", "global")
    if recorded != representation:
        raise LessonFileError(f"{path}: lessons were recorded with action_representation={recorded!r}, "
                              f"the agent uses {representation!r}")
    return lessons


def make_survival_agent(params: SurvivalAgentParams, env, rng: np.random.Generator):
    """Build one of the eight Ch. 4 agents; ``env`` is the live training env (the -M models step copies of it)."""
    p = params
    if env.action_representation != p.representation:
        raise ValueError(f"env uses action_representation={env.action_representation!r}, "
                         f"the agent {p.representation!r}")
    base, _, ext = p.framework.partition("-")
    table = table_4_1(p.framework)
    temperature = TemperatureSchedule.inverse(*table["inv_t"], over=p.plays)

    def net(lr: float) -> NetConfig:
        return NetConfig(145, p.hidden, value_range=1.0, init_range=p.init_range, lr=lr * p.lr_scale,
                         momentum=p.momentum)

    replay = None
    if ext in ("R", "T"):
        replay = ReplayConfig(capacity=100, lessons_per_trial=LinearSchedule(p.lessons_start, p.lessons_end, p.plays),
                              p_threshold=p.p_threshold if p.p_threshold is not None else (
                                  0.2 if base == "AHCON" else 0.01),
                              taught_probability=LinearSchedule(p.taught_start, p.taught_end, p.plays),
                              taught_p_threshold=0.0)
    planner = None
    if ext == "M":
        if p.model == "perfect":
            planner = RelaxationPlanner(PerfectSurvivalModel(env, rng), PlanningConfig(p.promising, 0))
        else:
            model = LearnedSurvivalModel(env, rng, LearnedModelConfig(momentum=p.momentum, init_range=p.init_range))
            planner = RelaxationPlanner(model, PlanningConfig(p.promising, p.model_start))
    stuck = StuckConfig(p.stuck_window, p.stuck_radius, p.stuck_boost)
    rotated = p.representation == "global" and p.symmetry
    if rotated:
        perms = np.stack([ROTATION_PERMUTATIONS[ACTION_ROTATION[a]] for a in range(4)])
    if base == "QCON":
        cfg = QCONConfig(net=net(table["lr_q"]), temperature=temperature, gamma=p.gamma, replay=replay,
                         target_clip=1.0, stuck=None)
        q = RotatedNet(cfg.net, perms, rng) if rotated else None
        agent = QCON(cfg, 4, rng, q=q, planner=planner)
    else:
        cfg = AHCONConfig(v_net=net(table["lr_v"]), policy_net=net(table["lr_p"]), temperature=temperature,
                          gamma=p.gamma, replay=replay, target_clip=1.0, stuck=None)
        policy = RotatedNet(cfg.policy_net, perms, rng) if rotated else None
        agent = AHCON(cfg, 4, rng, policy=policy, planner=planner)
    agent.explore = SurvivalExploration(temperature, stuck)
    if ext == "T":
        agent.add_taught_lessons(taught_lessons(p.representation))
    return agent


def make_taught_lessons(action_representation: str = "global", n_lessons: int = 2, seed: int = 0):
    """Taught lessons (3.7, 4.3.1) played by the scripted teacher (``connrl.envs.survival.scripted_teacher_lesson``).

    Like the thesis's teacher, who "got all the food in each of the lessons", we keep only plays in which
    the teacher eats all 15 pieces: layout seeds 0, 1, 2, ... (play seed = `seed` + layout seed) are tried
    in order and the first `n_lessons` complete plays are returned. Each lesson's ``meta`` records the
    layout seed, the play seed and the food cells, so the play can be re-run exactly.
    """
    env = SurvivalEnv(action_representation=action_representation)
    lessons = []
    for layout_seed in range(1000):
        options = {"layout_seed": layout_seed}
        env.reset(seed=seed + layout_seed, options=options)
        food_cells = np.argwhere(env.get_state()["food"]).tolist()
        steps, info = scripted_teacher_lesson(env, seed=seed + layout_seed, options=options)
        if info["outcome"] != "all_food":
            continue
        meta = {
            "teacher": "scripted_teacher_action(danger_radius=2)",
            "action_representation": action_representation,
            "layout_seed": layout_seed,
            "play_seed": seed + layout_seed,
            "food": food_cells,
            "food_eaten": info["food_eaten"],
            "outcome": info["outcome"],
        }
        lessons.append(Lesson.from_steps(steps, taught=True, meta=meta))
        if len(lessons) == n_lessons:
            return lessons
    raise RuntimeError(f"the scripted teacher completed fewer than {n_lessons} of 1000 environments")


# ------------------------------------------------------------------------------------------- tests (4.3)

def test_plays(env: SurvivalEnv, agent, layouts: list[int]) -> dict:
    """Greedy plays (learning off, T = 0) on the test environments; seeds fixed per environment so every
    test point sees the same enemy random streams (common random numbers)."""
    food, outcomes = [], {"all_food": 0, "killed": 0, "starved": 0}
    for k in layouts:
        stats = greedy_play(env, agent, k)
        food.append(stats.info["food_eaten"])
        outcomes[stats.info["outcome"]] = outcomes.get(stats.info["outcome"], 0) + 1
    return {"food": float(np.mean(food)), "food_per_env": food, **outcomes}


def evaluate(agent, representation: str, seed: int, n_envs: int, progress=lambda d: None) -> dict:
    """4.3.4: greedy plays on ``n_envs`` fresh random environments; outcome shares and the food histogram.
    The first play is also recorded step by step (``example_play``) for ``connrl.report.survival.render_play``."""
    env = SurvivalEnv(representation)
    _, layouts = environment_sets(seed, 0, n_envs)
    food, outcomes = np.zeros(16, dtype=np.int64), {"all_food": 0, "killed": 0, "starved": 0}
    example = []
    for i, k in enumerate(layouts):
        record = None
        if i == 0:
            def record(info):
                example.append(_frame(env))
            env.reset(seed=k, options={"layout_seed": k})
            example.append(_frame(env))
        stats = (run_trial(env, agent, trial=0, learning=False, seed=k, options={"layout_seed": k}, on_step=record)
                 if record else greedy_play(env, agent, k))
        food[stats.info["food_eaten"]] += 1
        outcomes[stats.info["outcome"]] += 1
        if i % 200 == 0:
            progress(i)
    n = float(n_envs)
    return {"eval_food": float(np.dot(np.arange(16), food) / n),
            "eval_all_food_pct": 100 * outcomes["all_food"] / n, "eval_killed_pct": 100 * outcomes["killed"] / n,
            "eval_starved_pct": 100 * outcomes["starved"] / n, "histogram_pct": (100 * food / n).tolist(),
            "example_play": example}


def _frame(env: SurvivalEnv) -> dict:
    s = env.get_state()
    return {"agent": list(s["agent"]), "enemies": s["enemies"].tolist(), "food": np.argwhere(s["food"]).tolist(),
            "energy": s["energy"], "orientation": s["orientation"], "food_eaten": s["food_eaten"],
            "steps": s["steps"], "outcome": s["outcome"]}


class FoodReward(gym.Wrapper):
    """The survival world with another reward for eating (4.2.1: 0.4 was "roughly the best" of a few values tried
    for AHCON); death stays -1 and wins when both happen in one step, as in the world itself."""

    def __init__(self, env, food: float):
        super().__init__(env)
        self.food = float(food)

    def step(self, action):
        obs, r, terminated, truncated, info = self.env.step(action)
        return obs, (self.food if r == REWARD_FOOD else r), terminated, truncated, info

