"""Ch. 6 wiring: the recharging task whose actions are the learned behaviours (6.5).

``BehaviourEnv`` wraps the world ``connrl.envs.robot.recharge.RechargeEnv`` (16 high-level inputs) and a behaviour
library (``connrl.tasks.behaviours``; the shipped one by default). Its action is a behaviour -- 0 DK, 1 DP, 2 WFL,
3 WFR -- and each step applies ONE primitive step of that behaviour's greedy policy, chosen on the behaviour's own
Ch. 5 observation of the current scan: the robot decides which behaviour to follow on every primitive step (6.5).
``info["applicable"]`` holds each behaviour's applicability (6.4.3) in the state reached, so a high-level learner can
weight its choices by W(b) (Eq. 6.6); ``info["primitive"]`` the primitive action taken; ``info["behaviour_goal"]``
whether that step reached the chosen behaviour's own goal (DK docked, DP into another room), which ends persistence
(6.6.3).
"""

from __future__ import annotations

import functools

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from connrl.agents import LinearSchedule, QCONConfig, ReplayConfig
from connrl.agents.behaviour_level import BehaviourQCON
from connrl.core.exploration import TemperatureSchedule
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, HIGH_SIZE, RechargeEnv
from connrl.nets import NetConfig
from connrl.tasks.behaviours import Behaviour, load_library


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
        primitive = self.library[task].act(self._task_obs[task])
        room = self.world.sim.room
        obs, r, terminated, truncated, info = self.world.step(primitive)
        # the behaviour's own goal (its reinforcement of 100 in Ch. 5): docked (DK), into another room (DP)
        goal = bool(info["success"]) if task == "DK" else (  # as Ch. 5's DP success: into another room, no collision
            task == "DP" and not info["collision"] and info["room"] != room)
        info["primitive"], info["behaviour"], info["behaviour_goal"] = primitive, task, goal
        return obs, r, terminated, truncated, self._with_applicability(info)

    @property
    def trace(self):
        return self.world.trace


@functools.lru_cache(maxsize=1)
def _shipped_library() -> dict[str, Behaviour]:
    return load_library()  # read once per process; behaviours are only read, never trained, here


def make_recharge_env(p) -> BehaviourEnv:
    """The behaviour-level task of a Ch. 6 parameter set (``connrl.experiments.recharge.RechargeParams``)."""
    return BehaviourEnv(_shipped_library(), max_steps=p.max_steps)


def make_high_level_agent(p, rng: np.random.Generator) -> BehaviourQCON:
    """Q(state, behaviour) of 6.5-6.6 from a Ch. 6 parameter set."""
    net = NetConfig(HIGH_SIZE, p.hidden, value_range=100.0, init_range=p.init_range, lr=p.lr, momentum=p.momentum)
    replay = ReplayConfig(capacity=p.capacity, lessons_per_trial=LinearSchedule(p.lessons_per_trial,
                                                                                p.lessons_per_trial),
                          p_threshold=0.0, p_threshold_oldest=p.p_oldest)
    cfg = QCONConfig(net=net, temperature=TemperatureSchedule.direct(p.t_start, p.t_end, p.trials), gamma=p.gamma,
                     lam=p.lam, online=p.online, replay=replay)
    return BehaviourQCON(cfg, len(BEHAVIOUR_TASKS), rng, persistence=p.persistence)
