"""Ch. 6, Experiment 5 wiring (6.6.5): the behaviours learn on, alongside the high-level learner.

Each behaviour is first trained alone for about 300 primitive steps with its taught lessons (10 DK and DP, 5 WFL and
WFR; "about 10-13 trials"; ``connrl.experiments.behaviours.pretrain_behaviours``). Then, while the high-level learner
chooses a behaviour on every primitive step, the chosen behaviour picks the primitive action by its own Boltzmann
exploration and learns from its own Ch. 5 reinforcement (``TrainingBehaviourEnv``). A run of consecutive steps of one
behaviour is one of its lessons (cut at Ch. 5's 30 steps, or when its goal is reached); each behaviour replays after
every high-level trial. Greedy tests use the same (live) Q-nets through a plain ``BehaviourEnv``.
"""

from __future__ import annotations

from connrl.agents.teaching import TeachingQCON
from connrl.envs.robot.tasks import R_COLLISION, R_SUCCESS, wall_following_reward
from connrl.tasks.behaviours import Behaviour
from connrl.tasks.recharge import BehaviourEnv

SEGMENT = 30  # steps of a behaviour's lesson at most: Ch. 5's trial length


def own_reward(task: str, action: int, collided: bool, docked: bool, passed: bool, true_ranges) -> float:
    """A behaviour's Ch. 5 reinforcement (5.3.1) for one primitive step of the recharging world: DK docked, DP into
    another room without a collision (each +100), a collision -10; wall following's 8-10 / 0 / -3 / -10."""
    if task == "DK":
        return R_SUCCESS if docked else (R_COLLISION if collided else 0.0)
    if task == "DP":
        return R_SUCCESS if passed else (R_COLLISION if collided else 0.0)
    return wall_following_reward(action, collided, true_ranges, "left" if task == "WFL" else "right")


class TrainingBehaviourEnv(BehaviourEnv):
    """``BehaviourEnv`` whose chosen behaviour explores and learns (module docstring); ``learn_behaviours()`` after
    each high-level trial replays every behaviour's lessons."""

    def __init__(self, agents: dict[str, TeachingQCON], start_trials: dict[str, int] | None = None, **world):
        super().__init__({t: Behaviour(t, a.q) for t, a in agents.items()}, **world)
        self.agents = agents
        self._segment: str | None = None
        self._seg_steps = 0
        # each behaviour's trial count, which its Ch. 5 schedules (T, lessons per trial) follow: its pre-training
        # trials, then one per lesson
        self._lessons = {t: int((start_trials or {}).get(t, 0)) for t in agents}

    def _close(self) -> None:
        if self._segment is not None:
            self.agents[self._segment].end_trial()
            self._lessons[self._segment] += 1
        self._segment, self._seg_steps = None, 0

    def reset(self, *, seed=None, options=None):
        self._close()
        return super().reset(seed=seed, options=options)

    def _primitive(self, task: str) -> int:
        agent, before = self.agents[task], self._task_obs[task]
        if self._segment != task:
            self._close()
            self._segment = task
            agent.begin_trial(before, {"pose": self.world.sim.pose}, trial=self._lessons[task], learning=True)
        return agent.act(before, {"pose": self.world.sim.pose})

    def _after(self, task: str, primitive: int, room, info: dict, goal: bool, ended: bool) -> None:
        collided = bool(info["collision"])
        passed = not collided and info["room"] != room
        mine = own_reward(task, primitive, collided, bool(info["success"]), passed,
                          self.world.sim.true_ranges() if task in ("WFL", "WFR") else None)
        self._seg_steps += 1
        cut = not goal and (self._seg_steps >= SEGMENT or ended)
        self.agents[task].observe(primitive, mine, info["task_obs"][task], goal, cut, info)
        if goal or cut:
            self._close()

    def learn_behaviours(self) -> None:
        self._close()
        for agent in self.agents.values():
            agent.learn()

