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

Builders take the experiment's parameters by attribute; the protocols beside them state what each reads.
"""

from __future__ import annotations

import functools
from typing import Protocol

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from connrl.agents import LinearSchedule, QCONConfig, ReplayConfig
from connrl.agents.behaviour_level import TARGET_MAX, BehaviourChoice, BehaviourQCON  # noqa: F401  (experiments see it through tasks)
from connrl.agents.teaching import TeachingConfig, TeachingQCON
from connrl.core.exploration import StuckConfig, TemperatureSchedule
from connrl.core.lesson_files import load_lessons, save_lessons
from connrl.core.lessons import Lesson
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, FLAT_SIZE, HIGH_SIZE, RechargeEnv
from connrl.envs.robot.teachers import teach_chg
from connrl.nets import NetConfig
from connrl.tasks.behaviours import Behaviour, load_library
from connrl.tasks.robot import LESSON_DIR

CHG_LESSONS = LESSON_DIR / "robot-chg.json"
CHG_TAUGHT = 10  # taught lessons of Experiment 1 (6.6.1)


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


class BehaviourTaskParams(Protocol):
    """What ``make_recharge_env`` reads (read-only, as the frozen parameter dataclasses are)."""

    @property
    def max_steps(self) -> int: ...
    @property
    def step_scale(self) -> float: ...
    @property
    def success_reward(self) -> float: ...
    @property
    def xy_scale(self) -> float: ...


class LearnerParams(Protocol):
    """The Q-nets, exploration and replay that every Ch. 6 and Ch. 8 learner's builder reads."""

    @property
    def hidden(self) -> int: ...
    @property
    def init_range(self) -> float: ...
    @property
    def lr(self) -> float: ...
    @property
    def momentum(self) -> float: ...
    @property
    def capacity(self) -> int: ...
    @property
    def lessons_per_trial(self) -> int: ...
    @property
    def t_start(self) -> float: ...
    @property
    def t_end(self) -> float: ...
    @property
    def trials(self) -> int: ...
    @property
    def gamma(self) -> float: ...
    @property
    def lam(self) -> float: ...


class HighLevelAgentParams(LearnerParams, Protocol):
    """What ``make_high_level_agent`` reads (``connrl.experiments.recharge.RechargeParams``)."""

    @property
    def success_reward(self) -> float: ...
    @property
    def p_oldest(self) -> float: ...
    @property
    def grouping(self) -> bool: ...
    @property
    def mu_low(self) -> float: ...
    @property
    def mu_high(self) -> float: ...
    @property
    def online(self) -> bool: ...
    @property
    def persistence(self) -> bool: ...
    @property
    def target_max(self) -> str: ...
    @property
    def replay_from_start(self) -> bool: ...
    @property
    def output_init(self) -> float: ...
    @property
    def cool_trials(self) -> int: ...


class FlatWorldParams(Protocol):
    """What ``make_flat_env`` reads (``connrl.experiments.recharge_flat.FlatParams``)."""

    @property
    def max_steps(self) -> int: ...
    @property
    def collision_penalty(self) -> float: ...


class FlatAgentParams(LearnerParams, Protocol):
    """What ``make_flat_agent`` reads (``connrl.experiments.recharge_flat.FlatParams``)."""

    @property
    def p_threshold(self) -> float: ...
    @property
    def online(self) -> bool: ...
    @property
    def stuck_window(self) -> int: ...
    @property
    def stuck_radius(self) -> float: ...
    @property
    def stuck_boost(self) -> float: ...
    @property
    def lessons(self) -> int: ...


def make_recharge_env(p: BehaviourTaskParams) -> BehaviourEnv:
    """The behaviour-level task of a Ch. 6 parameter set (``connrl.experiments.recharge.RechargeParams``)."""
    return BehaviourEnv(_shipped_library(), max_steps=p.max_steps, step_scale=p.step_scale,
                        success_reward=p.success_reward, xy_scale=p.xy_scale)


def cooling(p: HighLevelAgentParams) -> TemperatureSchedule:
    """The high level's T: from t_start to t_end over the first ``cool_trials`` trials, then held (6.6; the pace is
    ours, docs/RECONSTRUCTION.md); Ch. 8's recurrent learner takes the same."""
    return TemperatureSchedule.direct(p.t_start, p.t_end, min(p.cool_trials, p.trials))


def make_high_level_agent(p: HighLevelAgentParams, rng: np.random.Generator,
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


def make_flat_env(p: FlatWorldParams) -> RechargeEnv:
    """Experiment 1's world: the flat input, primitive actions (``connrl.experiments.recharge_flat.FlatParams``)."""
    return RechargeEnv(obs="flat", max_steps=p.max_steps, collision_penalty=p.collision_penalty)


def make_flat_agent(p: FlatAgentParams, rng: np.random.Generator) -> TeachingQCON:
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

