"""Ch. 6 wiring: the recharging task whose actions are the learned behaviours (6.5), and Experiment 1's flat learner.

``BehaviourEnv`` wraps the world ``connrl.envs.robot.recharge.RechargeEnv`` (16 high-level inputs; 14 with
``xy=False``, Ch. 8) and a behaviour
library (``connrl.tasks.behaviours``; the shipped one by default). Its action is a behaviour -- 0 DK, 1 DP, 2 WFL,
3 WFR -- and each step applies ONE primitive step of that behaviour's greedy policy, chosen on the behaviour's own
Ch. 5 observation of the current scan: the robot decides which behaviour to follow on every primitive step (6.5).
``info["applicable"]`` holds each behaviour's applicability (6.4.3) in the state reached, so a high-level learner can
weight its choices by W(b) (Eq. 6.6); ``info["primitive"]`` the primitive action taken; ``info["behaviour_goal"]``
whether that step reached the chosen behaviour's own goal (DK docked, DP into another room), which ends persistence
(6.6.3).

Experiment 1 (6.6.1) learns Q(state, action) on the flat input with QCON-T (``make_flat_agent``) and 10 taught
lessons of the scripted recharging teacher (``connrl.envs.robot.teachers.teach_chg``; ``connrl make-lessons robot``
writes them to ``connrl/data/lessons/robot-chg.json``).

The builders take ``RechargeParams``, ``FlatParams`` or ``BoundParams``, declared here beside them: each parameter
once, with its range and where the thesis states it (``connrl.core.params.param``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from connrl.agents import LinearSchedule, QCONConfig, ReplayConfig
from connrl.agents.behaviour_level import TARGET_MAX, BehaviourChoice, BehaviourQCON  # noqa: F401  (experiments see it through tasks)
from connrl.agents.teaching import TeachingConfig, TeachingQCON
from connrl.core.exploration import StuckConfig, TemperatureSchedule
from connrl.core.lesson_files import load_lessons, save_lessons
from connrl.core.lessons import Lesson
from connrl.core.params import check_types, param
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, FLAT_SIZE, HIGH_SIZE, RechargeEnv
from connrl.envs.robot.teachers import teach_chg
from connrl.nets import NetConfig
from connrl.tasks.behaviours import Behaviour, library_digest, load_library
from connrl.tasks.robot import LESSON_DIR

CHG_LESSONS = LESSON_DIR / "robot-chg.json"
CHG_TAUGHT = 10  # taught lessons of Experiment 1 (6.6.1)


SHIPPED_LIBRARY = library_digest()

WALLS = ("WFL", "WFR")

@dataclass(frozen=True)
class BoundParams:
    """The fixed rule's settings and the recharging task's (as ``RechargeParams``'s)."""

    position: bool = param(True, note="DP only near the door that leads on (needs X-Y); False: DP wherever applicable")
    history: bool = param(False, note="without position: in room C come from B, no DP while door B is in sight (Ch. 8)")
    near_door: float = param(60.0, ">0", "inches from the door's centre within which DP is taken (ours)")
    best_walls: bool = param(False, note="per task, the best of the 8 wall-follower choices (an oracle) instead of "
                             "wall_A/B/C")
    wall_A: str = param("WFL", note="wall follower per room (ours: development seeds 100-106)", choices=WALLS)
    wall_B: str = param("WFL", choices=WALLS)
    wall_C: str = param("WFR", choices=WALLS)
    max_steps: int = param(200, ">=1", "(6.6)")
    tests_per_room: int = param(10, ">=1", "as RechargeParams: the same test tasks for the same seed")
    step_scale: float = param(1.0, ">0")
    success_reward: float = param(100.0, ">0")
    xy_scale: float = param(8.0, ">0", "as RechargeParams's, so the world is the learners' (the rule reads the true "
                            "position)")
    library: str = SHIPPED_LIBRARY

    def __post_init__(self):
        check_types(self)
        if self.history and self.position:
            raise ValueError("parameter history applies without position only: use position=false with history=true")
        if self.library != SHIPPED_LIBRARY:
            raise ValueError(f"parameter library must be the shipped behaviour library's digest {SHIPPED_LIBRARY}, "
                             f"got {self.library!r}")


@dataclass(frozen=True)
class FlatParams:
    """One Experiment 1 run: 6.6.1's values, else Ch. 5's (5.3)."""

    lessons: int = param(CHG_TAUGHT, ">=0", "taught lessons (6.6.1: 10)")
    hidden: int = param(30, ">=1", "(6.6.1)")
    lr: float = param(0.05, ">0", "(6.6: fixed to 0.05)")
    momentum: float = param(0.9, "0..<1", "(Ch. 5)")
    init_range: float = param(0.5, ">0", "(Ch. 5)")
    gamma: float = param(0.99, "0..1", "(6.6.1)")
    lam: float = param(0.8, "0..1", "(6.6.1)")
    t_start: float = param(0.05, ">0", "(6.6)")
    t_end: float = param(0.02, ">0")
    capacity: int = param(100, ">=1", "(App. A.2, Ch. 5)")
    lessons_per_trial: int = param(60, ">=0", "(6.6)")
    p_threshold: float = param(0.02, "0..<1", "P_l (Ch. 5)")
    online: bool = param(True, note="(Ch. 5)")
    stuck_window: int = param(8, ">=1", "stuck detection (Ch. 5's)")
    stuck_radius: float = param(12.0, ">=0")
    stuck_boost: float = param(5.0, ">0")
    collision_penalty: float = param(0.0, note="(6.6.1: none; -5 and -10 also tried)")
    trials: int = param(300, ">=1", "(Fig. 6.5)")
    max_steps: int = param(200, ">=1", "(6.6)")
    test_every: int = param(10, ">=1")
    tests_per_room: int = param(10, ">=1", "as Exps 2-3")
    paths: int = param(0, ">=0", "greedy solution paths recorded per start room after the last trial")

    def __post_init__(self):
        check_types(self)
        if not self.collision_penalty <= 0:
            raise ValueError(f"parameter collision_penalty must be <= 0, got {self.collision_penalty}")
        if self.lessons > CHG_TAUGHT:
            raise ValueError(f"parameter lessons must be at most {CHG_TAUGHT} (the shipped recharging lessons), got "
                             f"{self.lessons}")


@dataclass(frozen=True)
class RechargeParams:
    """One Ch. 6 run: the thesis's values where 6.6 gives them, else Ch. 5's (R)."""

    persistence: bool = param(True, note="Exp. 3's persistence rule (6.5.1); False = Exp. 2")
    hidden: int = param(8, ">=1", "hidden units of each Q-net (6.6)")
    lr: float = param(0.05, ">0", "(6.6)")
    momentum: float = param(0.9, "0..<1", "(R, Ch. 5)")
    init_range: float = param(0.3, ">0", "(R) Ch. 5's 0.5 lets untrained nets differ by tens of Q units: a behaviour "
                              "falls below the others at once and is never tried again; 0.3 learns room B faster than "
                              "0.1 (docs/RECONSTRUCTION.md, 'High-level learner')")
    output_init: float = param(0.0, ">=0", "(R) hidden->output weights start at 0: every behaviour's Q starts at 0 "
                               "everywhere, so none starts below the others and goes untried (docs/RECONSTRUCTION.md, "
                               "'High-level learner')")
    gamma: float = param(0.99, "0..1", "(6.6.2)")
    lam: float = param(0.8, "0..1", "(6.6.2)")
    t_start: float = param(0.05, ">0", "T 0.05 -> 0.02 over the run, on Q / 100 (6.6; the scale as in Ch. 5)")
    t_end: float = param(0.02, ">0")
    cool_trials: int = param(60, ">=1", "(R) T cools from t_start to t_end over the first cool_trials trials, then "
                             "holds; the thesis gives the range, not the pace (docs/RECONSTRUCTION.md, 'High-level "
                             "learner')")
    lessons_per_trial: int = param(60, ">=0", "'approximately 60 lessons' (6.6)")
    replay_from_start: bool = param(True, note="(R) 60 replays from the first trial on, drawn from the lessons stored "
                                    "so far; False: no more replays than lessons stored (5.3.5's reading), which "
                                    "leaves the first trials nearly unlearnt")
    capacity: int = param(100, ">=1", "latest lessons kept (App. A.2)")
    p_oldest: float = param(0.02, "0..<1", "P_l from 0 for the latest lesson to this for the oldest (6.6)")
    online: bool = param(True, note="Q-learning on each step as well as replay (R, as Ch. 5)")
    trials: int = param(150, ">=1", "(Fig. 6.6 / 6.7: 'after 150 learning trials')")
    max_steps: int = param(200, ">=1", "(6.6)")
    test_every: int = param(10, ">=1")
    tests_per_room: int = param(10, ">=1", "fixed greedy test tasks per start room (R)")
    library: str = param(SHIPPED_LIBRARY, note="digest of the behaviour library (connrl train-behaviours): new "
                         "library, new runs")
    # the Q target's max over the behaviours "applicable" in the next state (R): only those can be chosen there (W > 0,
    # Eq. 6.6). "all" reads nets never trained where their behaviour is inapplicable (docs/RECONSTRUCTION.md)
    target_max: str = param("applicable", choices=TARGET_MAX)
    step_scale: float = param(1.0, ">0", "primitive actions shrunk to this fraction (Exp. 4, 6.6.4: 1/5)")
    xy_scale: float = param(8.0, ">0", "(R) the X-Y units in +-xy_scale/2: at +-0.5 the 8 hidden units barely tell "
                            "places in a room apart (docs/RECONSTRUCTION.md, 'High-level learner')")
    success_reward: float = param(100.0, ">0", "reinforcement for docking (6.4; Exp. 4: 500); Q-nets and T scale with "
                                  "it")
    grouping: bool = param(False, note="state grouping in replay (Exp. 4, 6.6.4) ...")
    mu_low: float = param(0.5, ">=0", "... with mu ~ U(mu_low, mu_high) per group (6.6.4)")
    mu_high: float = param(2.5, ">=0")
    paths: int = param(0, ">=0", "greedy solution paths recorded per start room after the last trial (Fig. 6.7)")
    pretrain_steps: int = param(0, ">=0", "Exp. 5 (6.6.5): behaviours pre-trained this many primitive steps, then "
                                "trained along with the high level; 0 = the shipped library, never trained further")

    def __post_init__(self):
        check_types(self)
        if self.step_scale > 1 or self.mu_low > self.mu_high:
            raise ValueError(f"parameter step_scale must be in (0, 1] and mu_low <= mu_high, got step_scale "
                             f"{self.step_scale}, mu ({self.mu_low}, {self.mu_high})")
        if self.library != SHIPPED_LIBRARY:
            raise ValueError(f"parameter library must be the shipped behaviour library's digest {SHIPPED_LIBRARY} "
                             f"(connrl train-behaviours changes it), got {self.library!r}")


class BehaviourEnv(gym.Env):
    """CHG over behaviours: ``Discrete(4)`` actions (DK, DP, WFL, WFR), the 16 high-level inputs (6.4.2)."""

    metadata = {"render_modes": [], "render_fps": 4}

    def __init__(self, library: dict[str, Behaviour] | str | None = None, **world):
        if world.get("obs", "high") != "high":
            raise ValueError("the behaviour-level task observes the 16 high-level inputs (obs='high')")
        if library is None:
            library = load_library()  # the shipped library
        self.library = load_library(library) if isinstance(library, str) else library
        missing = [t for t in BEHAVIOUR_TASKS if t not in self.library]
        if missing:
            raise ValueError(f"the behaviour library lacks {', '.join(missing)}; it needs {', '.join(BEHAVIOUR_TASKS)}")
        self.world = RechargeEnv(obs="high", **{k: v for k, v in world.items() if k != "obs"})
        self.observation_space = self.world.observation_space
        self.action_space = spaces.Discrete(len(BEHAVIOUR_TASKS))
        self._task_obs: dict | None = None

    def _with_applicability(self, info: dict) -> dict:
        self._task_obs = info["task_obs"]
        info["applicable"] = np.array([self.library[t].applicable(self._task_obs[t]) for t in BEHAVIOUR_TASKS])
        return info

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        obs, info = self.world.reset(seed=seed, options=options)
        return obs, self._with_applicability(info)

    def step(self, action):
        if self._task_obs is None:
            raise RuntimeError("call reset() before step()")
        b = int(action)
        if b != action or not 0 <= b < len(BEHAVIOUR_TASKS):
            raise ValueError(f"action must be a behaviour 0..3 {BEHAVIOUR_TASKS}, got {action!r}")
        task = BEHAVIOUR_TASKS[b]
        primitive = self._primitive(task)
        room = self.world.sim.room
        obs, r, terminated, truncated, info = self.world.step(primitive)
        # the behaviour's own goal (its reinforcement of 100 in Ch. 5): docked (DK), into another room without a
        # collision (DP, as Ch. 5's success)
        goal = bool(info["success"]) if task == "DK" else (
            task == "DP" and not info["collision"] and info["room"] != room)
        self._after(task, primitive, room, info, goal, terminated or truncated)
        info["primitive"], info["behaviour"], info["behaviour_goal"] = primitive, task, goal
        return obs, r, terminated, truncated, self._with_applicability(info)

    def _primitive(self, task: str) -> int:
        """The primitive action the behaviour takes now: its greedy one."""
        return self.library[task].act(self._task_obs[task])

    def _after(self, task: str, primitive: int, room, info: dict, goal: bool, ended: bool) -> None:
        """Hook after each primitive step (``room``: the room before it); behaviours that learn use it."""

    @property
    def trace(self):
        return self.world.trace


@functools.lru_cache(maxsize=1)
def _shipped_library() -> dict[str, Behaviour]:
    return load_library()  # read once per process; behaviours are only read, never trained, here


def make_recharge_env(p: RechargeParams | BoundParams) -> BehaviourEnv:
    """The behaviour-level task of a Ch. 6 parameter set (``RechargeParams``)."""
    return BehaviourEnv(_shipped_library(), max_steps=p.max_steps, step_scale=p.step_scale,
                        success_reward=p.success_reward, xy_scale=p.xy_scale)


def cooling(p: RechargeParams) -> TemperatureSchedule:
    """The high level's T: from t_start to t_end over the first ``cool_trials`` trials, then held (6.6; the pace is
    ours, docs/RECONSTRUCTION.md); Ch. 8's recurrent learner takes the same."""
    return TemperatureSchedule.direct(p.t_start, p.t_end, min(p.cool_trials, p.trials))


def make_high_level_agent(p: RechargeParams, rng: np.random.Generator,
                          n_inputs: int = HIGH_SIZE) -> BehaviourQCON:
    """Q(state, behaviour) of 6.5-6.6 from a Ch. 6 parameter set (``n_inputs``: 14 without X-Y, Ch. 8)."""
    # Q in +-success_reward and T on Q / success_reward, so Exp. 4's reward of 500 keeps Exp. 3's choices (6.6.4)
    net = NetConfig(n_inputs, p.hidden, value_range=p.success_reward, init_range=p.init_range, lr=p.lr,
                    momentum=p.momentum, output_init=p.output_init)
    replay = ReplayConfig(capacity=p.capacity, lessons_per_trial=LinearSchedule(p.lessons_per_trial,
                                                                                p.lessons_per_trial),
                          p_threshold=0.0, p_threshold_oldest=p.p_oldest,
                          grouping=(p.mu_low, p.mu_high) if p.grouping else None)
    cfg = QCONConfig(net=net, temperature=cooling(p), gamma=p.gamma, lam=p.lam, online=p.online, replay=replay)
    agent = BehaviourQCON(cfg, len(BEHAVIOUR_TASKS), rng, BehaviourChoice(persistence=p.persistence,
                                                                          target_max=p.target_max),
                          merit_scale=p.success_reward)
    agent.replay_at_most_stored = not p.replay_from_start  # (R) RechargeParams.replay_from_start
    return agent


def make_chg_lessons(n: int = CHG_TAUGHT, seed: int = 0, max_tries: int = 100) -> list[Lesson]:
    """Demonstrations of the recharging teacher on the flat task, the k-th from room B, C, A in turn (so every
    room is taught), kept when they dock (positive examples, as Ch. 5's). Deterministic given ``seed``."""
    env = RechargeEnv(obs="flat")
    rng = np.random.default_rng(seed)
    out: list[Lesson] = []
    for i in range(max_tries):
        if len(out) == n:
            break
        room = ("B", "C", "A")[len(out) % 3]
        start = env.sample_start(rng, room)
        play_seed = int(rng.integers(2**31))
        steps = teach_chg(env, start, seed=play_seed)
        if not steps[-1][4]:
            continue
        out.append(Lesson.from_steps(steps, taught=True, meta={
            "teacher": "connrl.envs.robot.teachers.teach_chg", "room": room, "start": [round(v, 3) for v in start],
            "play_seed": play_seed, "attempt": i, "steps": len(steps), "success": True}))
    if len(out) < n:
        raise RuntimeError(f"the recharging teacher docked only {len(out)} times in {max_tries} tries")
    return out


def write_chg_lessons(seed: int = 0):
    """Regenerate connrl/data/lessons/robot-chg.json (``connrl make-lessons robot``)."""
    lessons = make_chg_lessons(seed=seed)
    save_lessons(CHG_LESSONS, lessons, env_id="connrl/Robot-CHG-Flat-v0", env_kwargs={},
                 source=f"connrl.tasks.recharge.make_chg_lessons(n={len(lessons)}, seed={seed}): scripted teacher, "
                        "not a person")
    return CHG_LESSONS


def chg_lessons(n: int) -> list[Lesson]:
    """The first ``n`` shipped taught lessons of the flat recharging task."""
    lessons = load_lessons(CHG_LESSONS, env_id="connrl/Robot-CHG-Flat-v0", input_dim=FLAT_SIZE, n_actions=6)
    if n > len(lessons):
        raise ValueError(f"CHG: {n} taught lessons asked for, the file has {len(lessons)}")
    return lessons[:n]


def make_flat_env(p: FlatParams) -> RechargeEnv:
    """Experiment 1's world: the flat input, primitive actions (``FlatParams``)."""
    return RechargeEnv(obs="flat", max_steps=p.max_steps, collision_penalty=p.collision_penalty)


def make_flat_agent(p: FlatParams, rng: np.random.Generator) -> TeachingQCON:
    """Experiment 1's monolithic QCON-T: "the same learning technique used to train the elementary behaviors"
    (6.6.1), i.e. Ch. 5's, with Ch. 6's gamma, lambda and net size."""
    net = NetConfig(FLAT_SIZE, p.hidden, value_range=100.0, init_range=p.init_range, lr=p.lr, momentum=p.momentum)
    replay = ReplayConfig(capacity=p.capacity, lessons_per_trial=LinearSchedule(p.lessons_per_trial,
                                                                                p.lessons_per_trial),
                          p_threshold=p.p_threshold)
    cfg = QCONConfig(net=net, temperature=TemperatureSchedule.direct(p.t_start, p.t_end, p.trials), gamma=p.gamma,
                     lam=p.lam, online=p.online, replay=replay,
                     stuck=StuckConfig(p.stuck_window, p.stuck_radius, p.stuck_boost))
    agent = TeachingQCON(cfg, 6, rng, TeachingConfig(merit_scale=100.0))
    agent.add_taught_lessons(chg_lessons(p.lessons))
    return agent

