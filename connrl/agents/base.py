"""The agent protocol and the pieces QCON and AHCON share (replay settings, schedules, lesson bookkeeping).

A run drives an agent like this (``connrl.core.rollout.run_trial``)::

    agent.begin_trial(obs, info, trial=k, learning=True)
    while not done:
        a = agent.act(obs, info, greedy=not learning)
        obs, r, terminated, truncated, info = env.step(a)
        if learning:
            agent.observe(a, r, obs, terminated, truncated, info)
    agent.end_trial()          # files the lesson (learning trials only)
    agent.learn()              # experience replay after the trial (3.5), if configured

``observe`` does the on-line update of Figs. 3.2/3.4; ``learn`` replays lessons (Fig. 5.1).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from connrl.core.exploration import StuckConfig, StuckDetector
from connrl.core.grouping import check_mu_range
from connrl.core.lessons import Lesson, LessonMemory, LessonRecorder, MixedOptions
from connrl.core.replay import ReplayParams


class Agent(Protocol):
    n_actions: int

    def begin_trial(self, obs, info: dict | None = None, *, trial: int = 0, learning: bool = True) -> None: ...

    def act(self, obs, info: dict | None = None, *, greedy: bool = False) -> int: ...

    def observe(self, action: int, reward: float, next_obs, terminated: bool, truncated: bool,
                info: dict | None = None) -> None: ...

    def end_trial(self) -> None: ...

    def learn(self) -> None: ...


@dataclass(frozen=True)
class LinearSchedule:
    """A value moving linearly from ``start`` to ``end`` over ``over`` trials (e.g. lessons per play 12 -> 4)."""

    start: float  # value at trial 0
    end: float  # value from trial over-1 on
    over: int = 1  # trials of the ramp

    def __call__(self, trial: int) -> float:
        frac = min(max(trial, 0) / max(self.over - 1, 1), 1.0)
        return self.start + (self.end - self.start) * frac


TAUGHT_ORDERS = ("after", "shuffled")


@dataclass(frozen=True)
class ReplayConfig:
    """Experience replay settings (3.5, 5.1, App. A.2)."""

    capacity: int = 100  # latest lessons kept for replay (App. A.2: 100; 7.5: 70)
    lessons_per_trial: LinearSchedule = LinearSchedule(12, 4, 300)  # lessons replayed after a trial (4.2.7)
    p_threshold: float = 0.01  # P_t: non-policy threshold for the latest lesson (3.5.1; Ch. 4: 0.2 AHC, 0.01 Q)
    p_threshold_oldest: float | None = None  # if set, P_t moves log-linearly to it for the oldest lesson (App. B)
    batch: bool = False  # batch-mode replay (5.1.2; recurrent nets, 7.5)
    taught_probability: LinearSchedule = LinearSchedule(1.0, 1.0)  # chance a taught lesson is replayed (4.2.7)
    taught_p_threshold: float = 0.0  # P_t for taught lessons (3.7: 0 for near-optimal teachers)
    taught_order: str = "after"  # "after" the experienced lessons, or "shuffled" in among them (not in the thesis)
    grouping: tuple[float, float] | None = None  # state grouping (6.6.4): mu ~ U(low, high); None = off

    def __post_init__(self):
        if self.capacity < 1:
            raise ValueError(f"replay capacity must be >= 1 lesson, got {self.capacity}")
        if self.taught_order not in TAUGHT_ORDERS:
            raise ValueError(f"taught_order must be one of {', '.join(TAUGHT_ORDERS)}, got {self.taught_order!r}")
        if self.grouping is not None:
            try:
                check_mu_range(self.grouping)
            except ValueError:
                raise ValueError(f"grouping must be None or (mu_low, mu_high) with 0 <= low <= high, both finite, got "
                                 f"{self.grouping!r}") from None
        for name in ("p_threshold", "taught_p_threshold"):
            v = getattr(self, name)
            if not 0 <= v < 1:
                raise ValueError(f"{name} must be in [0, 1), got {v}")

    def threshold_for_age(self, age: int) -> float:
        """P_t for a lesson ``age`` trials old (0 = the latest): log-linear from ``p_threshold`` to
        ``p_threshold_oldest`` (App. B), or linear when the latest's is 0 (6.6: "between 0 and 0.02")."""
        if self.p_threshold_oldest is None or self.capacity == 1:
            return self.p_threshold
        frac = min(age / (self.capacity - 1), 1.0)
        if self.p_threshold == 0:
            return self.p_threshold_oldest * frac
        lo, hi = math.log(self.p_threshold), math.log(self.p_threshold_oldest)
        return math.exp(lo + (hi - lo) * frac)


class LessonBook:
    """Records the current trial and keeps experienced and taught lessons for replay."""

    def __init__(self, replay: ReplayConfig | None):
        self.recorder = LessonRecorder()
        self.memory = LessonMemory(replay.capacity) if replay is not None else None
        self.taught: list[Lesson] = []
        self.ended: tuple[bool, bool] = (False, False)

    def close_trial(self) -> Lesson | None:
        lesson = self.recorder.finish(*self.ended)
        if lesson is not None and self.memory is not None:
            self.memory.add(lesson)
        self.ended = (False, False)
        return lesson


def position_of(info: dict | None):
    """Where the agent is, for stuck detection: ``info['position']`` or the x-y of ``info['pose']``."""
    if not info:
        return None
    if "position" in info:
        return info["position"]
    if "pose" in info:
        return np.asarray(info["pose"])[:2]
    return None


# What a compiled training loop does in place of the learner's own methods (connrl.tasks.survival_train,
# robot_train, recharge_train, cup_play): a method replaced on the instance of any of these parts is not called
# there, so that trial takes the Python path.
_LOOP_METHODS = {"": ("act", "observe", "next_value", "temperature", "encode", "begin_trial", "online_target",
                      "q_input"),
                 "q": ("values", "value", "update", "update_error"), "policy": ("values", "update_error"),
                 "v": ("value", "update"), "explore": ("temperature", "begin"), "explore.detector": ("factor",),
                 "book.recorder": ("add",), "net": ("values", "outputs", "advance"),
                 "model": ("step", "outputs", "advance"), "memory": ("push", "encode", "reset"),
                 "choice": ("choose", "weights", "observed", "next_value")}


def methods_replaced(agent) -> bool:
    """Whether a method a compiled training loop stands in for is replaced on the instance of the agent or its parts."""
    for path, names in _LOOP_METHODS.items():
        obj = agent
        for part in path.split(".") if path else ():
            obj = getattr(obj, part, None)
        if obj is not None and any(n in getattr(obj, "__dict__", {}) for n in names):
            return True
    return False


class Exploration:
    """Temperature of the current trial, optionally raised by stuck detection (4.2.6, 5.3.4)."""

    def __init__(self, schedule, stuck: StuckConfig | None):
        self.schedule = schedule
        self.detector = StuckDetector(stuck) if stuck is not None else None
        self.base = schedule(0)

    def begin(self, trial: int) -> None:
        self.base = self.schedule(trial)
        if self.detector is not None:
            self.detector.reset()

    def temperature(self, info: dict | None) -> float:
        if self.detector is None:
            return self.base
        pos = position_of(info)
        return self.base * (self.detector.factor(pos) if pos is not None else 1.0)


class LearnerConfig(Protocol):
    """What every learner's config holds (QCONConfig, AHCONConfig, RecurrentQConfig, RecurrentModelConfig)."""

    temperature: object  # Boltzmann temperature over trials: a callable trial -> T
    gamma: float
    lam: float
    replay: ReplayConfig | None
    target_clip: float | None


class LessonAgent:
    """The shared base of the thesis's learners (QCON, AHCON, their -R/-T/-M forms, the memory agents, the
    behaviour-level learners): the constructor, input encoding, the temperature, the on-line target, the replay
    settings (built once), lesson filing and the replay schedule of ``learn``. Subclasses make their nets and
    implement ``act``, ``observe`` and ``replay_lesson(lesson, p_threshold)``.

    ``merit_scale``: the Boltzmann choice, on-line and in replay's non-policy test, sees merits / ``merit_scale``
    (Ch. 5 and 6: Q in +-100, temperatures on the +-1 scale). ``batch`` overrides ``config.replay.batch`` for
    learners that replay only in batch mode (recurrent-Q, 7.5).
    """

    # replay no more experienced lessons than are stored: "fewer lessons were replayed in the beginning"
    # (5.3.5, footnote 1); Ch. 4 samples n lessons with replacement from the start (App. A.2)
    replay_at_most_stored: bool = False

    def __init__(self, config: LearnerConfig, n_actions: int, rng: np.random.Generator, *,
                 stuck: StuckConfig | None = None, merit_scale: float = 1.0, batch: bool | None = None):
        if not merit_scale > 0:
            raise ValueError(f"merit_scale must be > 0, got {merit_scale}")
        self.config, self.n_actions, self.rng = config, n_actions, rng
        self.merit_scale = float(merit_scale)
        self.explore = Exploration(config.temperature, stuck)
        self.book = LessonBook(config.replay)
        self.trial, self.learning = 0, True
        self._x: np.ndarray | None = None
        self.last_probabilities: np.ndarray | None = None
        r = config.replay
        self._made_params: tuple = (None, None, {})  # replay_params' (base params, temperature, {P_t: params})
        self._replay = ReplayParams(gamma=config.gamma, lam=config.lam, clip=config.target_clip,
                                    batch=(r is not None and r.batch) if batch is None else batch)

    def temperature(self, info: dict | None, greedy: bool) -> float:
        """T of this step's Boltzmann choice on the raw merits: 0 when greedy, else the trial's (raised when stuck)
        times ``merit_scale``."""
        return 0.0 if greedy else self.explore.temperature(info) * self.merit_scale

    def online_target(self, reward: float, next_value: float) -> float:
        """Fig. 3.2 / 3.4 step 4: r + gamma * next_value, truncated at ``target_clip`` (4.2.4). The caller passes
        next_value 0 at a terminal state only: a time limit is not one, and the target bootstraps through it."""
        target = reward + self.config.gamma * next_value
        clip = self.config.target_clip
        return target if clip is None else min(target, clip)

    def replay_params(self, p_threshold: float) -> ReplayParams:
        """How the next lesson is replayed (Fig. 5.1): the non-policy test at this trial's temperature (on the
        ``merit_scale`` the choice used) with threshold ``p_threshold``. Kept for the next lesson asking the same:
        a trial replays up to 1000 lessons at one temperature and a few thresholds (issue 45)."""
        t, (replay, cached_t, made) = self.explore.base * self.merit_scale, self._made_params
        if replay is not self._replay or cached_t != t:
            made = {}
            self._made_params = (self._replay, t, made)
        params = made.get(p_threshold)
        if params is None:
            params = made[p_threshold] = dataclasses.replace(self._replay, temperature=t, p_threshold=p_threshold)
        return params

    def encode(self, obs) -> np.ndarray:
        """Network input for an observation; memoryless agents feed the observation as it is."""
        return np.asarray(obs, dtype=np.float64).ravel()

    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = True) -> None:
        self.trial, self.learning = trial, learning
        self.explore.begin(trial)
        self._x = self.encode(obs)

    def end_trial(self) -> Lesson | None:
        """File the trial's lesson (learning trials only) and return it; a test trial's experiences are dropped."""
        if self.learning:
            return self.book.close_trial()
        self.book.recorder.finish(False, False)
        return None

    def took_compiled_trial(self, inputs: np.ndarray, actions: np.ndarray, rewards: np.ndarray, terminated: bool,
                            probabilities: np.ndarray) -> None:
        """The learner as ``run_trial`` leaves it before ``end_trial`` after a trial a compiled loop played
        (``connrl.tasks.survival_train``, ``robot_train``, ``recharge_train``, ``cup_play``): its n steps' n + 1
        inputs, actions and rewards in the recorder, the trial's end (a time limit when not terminated), its last
        input and its last choice's distribution."""
        rec = self.book.recorder
        rec.inputs, rec.actions, rec.rewards = list(inputs), actions.tolist(), rewards.tolist()
        self.book.ended = (bool(terminated), not terminated)
        self._x, self.last_probabilities = inputs[-1].copy(), probabilities

    def add_taught_lessons(self, lessons: list[Lesson]) -> None:
        """Teaching (3.7): taught lessons are replayed like experienced ones, with P_t = 0 by default."""
        for lesson in lessons:
            lesson.taught = True
            self.book.taught.append(lesson)

    def replay_lesson(self, lesson: Lesson, p_threshold: float) -> None:
        raise NotImplementedError

    # The ``replay_lesson`` functions that a class's ``replay_lessons`` does the work of, in one call.
    one_call_reproduces: tuple = ()

    def replays_in_one_call(self) -> bool:
        """Whether ``replay_lessons`` replays a trial's lessons in one compiled call, drawing nothing from the
        agent's generator (so a trial's lesson draws may all come first). Never when ``replay_lesson`` is not one
        it reproduces: replaced on the instance, or by a subclass the one call would bypass."""
        return "replay_lesson" not in vars(self) and type(self).replay_lesson in self.one_call_reproduces

    def replay_lessons(self, lessons: list[Lesson], thresholds: list[float]) -> None:
        """Replay ``lessons`` in turn, lesson k at P_t ``thresholds[k]``: in one call (``replay_in_one_call``) where
        ``replays_in_one_call``, else ``replay_lesson`` on each. A mix of lessons with and without per-step options
        (a behaviour-level trial begun without applicability) is refused by the one call before any replay, and
        replayed one by one."""
        if self.replays_in_one_call():
            try:
                self.replay_in_one_call(lessons, thresholds, self.replay_params(thresholds[0] if thresholds else 0.0))
                return
            except MixedOptions:
                pass
        for lesson, p_threshold in zip(lessons, thresholds, strict=True):
            self.replay_lesson(lesson, p_threshold)

    def replay_in_one_call(self, lessons: list[Lesson], thresholds: list[float], params: ReplayParams) -> None:
        """The one compiled call of a class whose ``one_call_reproduces`` names its ``replay_lesson``; ``params``
        holds the trial's settings but P_t, which ``thresholds`` gives lesson by lesson."""
        raise NotImplementedError

    def lesson_options(self, lesson: Lesson) -> tuple[np.ndarray | None, np.ndarray | None]:
        """The per-step (weights, allowed) a lesson is replayed with (``connrl.core.replay.replay_q``'s): none here."""
        return None, None

    def learn(self) -> None:
        """After a trial: replay n experienced lessons chosen by App. A.2 and the taught lessons (3.5, 3.7), the
        taught ones after the others or, with ``taught_order="shuffled"``, at random places among them (the
        thesis does not say which; docs/RECONSTRUCTION.md, "Learners and protocols")."""
        r = self.config.replay
        if r is None or not self.learning:
            return
        mem = self.book.memory
        n = int(round(r.lessons_per_trial(self.trial))) if len(mem) else 0
        if self.replay_at_most_stored:
            n = min(n, len(mem))
        p_taught = r.taught_probability(self.trial)
        if r.taught_order == "after":  # draws interleaved with replays, as the streams of stored runs expect
            if self.replays_in_one_call():  # its replays draw nothing: the same stream with the draws first
                ages = mem.sample_ages(self.rng, n)
                thresholds = {age: r.threshold_for_age(age) for age in set(ages)}
                lessons = mem.lessons
                self.replay_lessons([lessons[-1 - age] for age in ages], [thresholds[age] for age in ages])
            else:
                for _ in range(n):
                    age, lesson = mem.sample(self.rng)
                    self.replay_lesson(lesson, r.threshold_for_age(age))
            for lesson in self.book.taught:
                if p_taught >= 1 or self.rng.random() < p_taught:
                    self.replay_lesson(lesson, r.taught_p_threshold)
            return
        queue = [(lesson, r.threshold_for_age(age)) for age, lesson in (mem.sample(self.rng) for _ in range(n))]
        queue += [(lesson, r.taught_p_threshold) for lesson in self.book.taught
                  if p_taught >= 1 or self.rng.random() < p_taught]
        for i in self.rng.permutation(len(queue)):
            self.replay_lesson(*queue[i])
