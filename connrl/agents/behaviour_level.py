"""The high-level learner of Ch. 6: Q(state, behaviour) over learned behaviours (6.5), QCON with Eq. 6.6's choice.

On every primitive step it chooses a behaviour b with probability ``W(b) exp(Q(x, b)/T) / sum_k W(b_k) exp(Q(x,
b_k)/T)``. W comes from the environment's ``info["applicable"]`` (6.4.3): 0 for an inapplicable behaviour, 1 otherwise
(Experiment 2), and with ``persistence`` 100 for the behaviour being followed until its own goal is reached or a
behaviour becomes applicable (Experiment 3, 6.5.1; ``info["behaviour_goal"]``). Each step's W is kept with its lesson
so that replay drops the choices Eq. 6.6 then gave less than P_l ("bad behavior choices were not replayed", 6.6).
With ``target_max="applicable"`` the Q target's max (on-line and in replay) ranges over the behaviours applicable in
the next state only, whose nets may never have been trained there otherwise; ``"all"`` takes it over all four.
Temperatures act on Q / ``merit_scale`` (Q in +-100 with the reward of 100), as for Ch. 5's skills.

``BehaviourRecurrentQ`` is Ch. 8's learner (8.3): the same choice over behaviours, with recurrent Q-nets (7.3's
recurrent-Q: context units reset each trial, advanced by the chosen behaviour's net) learning only by batch replay,
one BPTT step per replayed lesson, with the same W-weighted non-policy test and applicable-only target max.

Both learners are handed a ``BehaviourChoice``: the rule that makes W, the choice it weights, and what each lesson
keeps of it (W per step, applicability per state).
"""

from __future__ import annotations

import numpy as np

from connrl.agents.memory import RecurrentQ, RecurrentQConfig, replay_recurrent_q
from connrl.agents.qcon import QCON, QCONConfig
from connrl.core.exploration import persistence_weights, weighted_boltzmann_probabilities
from connrl.core.lessons import Lesson

TARGET_MAX = ("all", "applicable")


def _applicable(info: dict) -> np.ndarray:
    return np.asarray(info["applicable"], dtype=bool)


class BehaviourChoice:
    """Eq. 6.6's weighted choice among behaviours, and what replay keeps of it. It holds the current trial's choices
    (the active behaviour, each step's W): one per learner, never shared.

    ``persistence``: Experiment 3's W of ``persist_weight`` for the behaviour being followed (6.5.1).
    ``target_max``: "applicable" takes the Q target's max over the next state's applicable behaviours (on-line and in
    replay), "all" over every behaviour.
    """

    def __init__(self, *, persistence: bool = False, persist_weight: float = 100.0, target_max: str = "all"):
        if not persist_weight > 0:
            raise ValueError(f"persist_weight must be > 0, got {persist_weight}")
        if target_max not in TARGET_MAX:
            raise ValueError(f"target_max must be one of {TARGET_MAX}, got {target_max!r}")
        self.persistence, self.persist_weight, self.target_max = bool(persistence), float(persist_weight), target_max
        self.begin_trial(None)

    def begin_trial(self, info: dict | None) -> None:
        self._active, self._was_applicable, self._w = None, None, None
        self._trial_weights: list[np.ndarray] = []
        self._trial_applicable = [_applicable(info)] if info is not None and "applicable" in info else []

    def weights(self, info: dict, applicable: np.ndarray | None = None) -> np.ndarray:
        """W(b) for the state of ``info`` (applicability, and the persistence rule when on); ``applicable``: that
        state's applicability if the caller already read it."""
        applicable = _applicable(info) if applicable is None else applicable
        if not self.persistence:
            return applicable.astype(np.float64)
        return persistence_weights(applicable, self._was_applicable, self._active,
                                   bool(info.get("behaviour_goal", False)), self.persist_weight)

    def choose(self, q: np.ndarray, info: dict | None, t: float, rng: np.random.Generator) -> tuple[int, np.ndarray]:
        """(behaviour, Eq. 6.6's probabilities) at temperature ``t`` on the raw Q-values; t = 0 takes the first
        best without a draw, so greedy tests never move the learner's random stream."""
        if info is None or "applicable" not in info:
            raise ValueError("a behaviour-level learner needs info['applicable'] from a behaviour-level environment "
                             "(connrl.tasks.recharge.BehaviourEnv)")
        applicable = _applicable(info)
        w = self.weights(info, applicable)
        if t == 0 and applicable.any() and q.shape == applicable.shape:  # Eq. 6.6 at T = 0 (every greedy test
            # step): W acts only as W > 0, which is applicability (persist_weight > 0 is checked in __init__), so the
            # first best applicable one, without the general function's checks
            best = applicable & (q == q[applicable].max())
            b, p = int(best.argmax()), best / best.sum()
        else:
            p = weighted_boltzmann_probabilities(q, w, t)
            b = int(p.argmax()) if t == 0 else int(rng.choice(p.size, p=p))
        self._active, self._was_applicable, self._w = b, applicable, w
        return b, p

    def observed(self, info: dict | None) -> None:
        """A learning step ended in the state of ``info``: keep the step's W and the new state's applicability."""
        if self.target_max == "applicable" and (info is None or "applicable" not in info):
            raise ValueError("target_max='applicable' needs info['applicable'] of the next state from a "
                             "behaviour-level environment (connrl.tasks.recharge.BehaviourEnv)")
        self._trial_weights.append(self._w)
        if info is not None and "applicable" in info:
            self._trial_applicable.append(_applicable(info))

    def file(self, lesson: Lesson | None) -> None:
        """Keep with the trial's lesson the W of each step (the non-policy test) and each state's applicability
        (the target's max)."""
        if lesson is None:
            return
        lesson.meta["weights"] = np.array(self._trial_weights)
        if len(self._trial_applicable) == len(lesson) + 1:
            lesson.meta["applicable"] = np.array(self._trial_applicable)

    def next_value(self, q_next: np.ndarray, info: dict | None) -> float:
        """The target's max over the next state's Q-values: over its applicable behaviours with
        ``target_max="applicable"`` (all of them when none is), the rule replay's ``allowed`` mask applies too."""
        if self.target_max == "all":
            return float(q_next.max())
        ok = _applicable(info)
        return float(q_next[ok].max() if ok.any() else q_next.max())

    def replay_options(self, lesson: Lesson, weights, allowed) -> tuple[np.ndarray | None, np.ndarray | None]:
        """(W per step, allowed behaviours per state) kept with ``lesson``; never the caller's."""
        if weights is not None or allowed is not None:
            raise ValueError("behaviour-level learners replay the weights and applicability kept with each lesson")
        return lesson.meta.get("weights"), lesson.meta.get("applicable") if self.target_max == "applicable" else None


class BehaviourQCON(QCON):
    """QCON over behaviours with W(b) of Eq. 6.6 (see the module docstring)."""

    replay_at_most_stored = True  # "approximately 60 lessons" (6.6): fewer while fewer are stored, as in 5.3.5;
    # Ch. 6's builders turn it off (RechargeParams.replay_from_start: 60 from the first trial on)

    def __init__(self, config: QCONConfig, n_behaviours: int, rng: np.random.Generator,
                 choice: BehaviourChoice | None = None, *, merit_scale: float = 100.0):
        super().__init__(config, n_behaviours, rng, merit_scale=merit_scale)
        self.choice = choice if choice is not None else BehaviourChoice()

    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = True) -> None:
        super().begin_trial(obs, info, trial=trial, learning=learning)
        self.choice.begin_trial(info)

    def act(self, obs, info=None, *, greedy: bool = False) -> int:
        if not self.learning or self._x is None:
            self._x = self.encode(obs)
        self.last_q = self.q.values(self._x)
        b, self.last_probabilities = self.choice.choose(self.last_q, info, self.temperature(info, greedy), self.rng)
        return b

    def observe(self, action, reward, next_obs, terminated, truncated, info=None) -> None:
        self.choice.observed(info)  # first: a missing info['applicable'] is refused before the step is learned from
        super().observe(action, reward, next_obs, terminated, truncated, info)

    def next_value(self, y: np.ndarray, info: dict | None) -> float:
        return self.choice.next_value(self.q.values(y), info)

    def end_trial(self) -> Lesson | None:
        lesson = super().end_trial()
        self.choice.file(lesson)
        return lesson

    def replay_lesson(self, lesson: Lesson, p_threshold: float, weights=None, allowed=None) -> None:
        """Replay with the W each step was chosen under and (``target_max="applicable"``) each state's applicable
        behaviours, both kept with the lesson."""
        super().replay_lesson(lesson, p_threshold, *self.choice.replay_options(lesson, weights, allowed))

    one_call_reproduces = (replay_lesson,)  # replay_lessons' one call does its work

    def lesson_options(self, lesson: Lesson) -> tuple[np.ndarray | None, np.ndarray | None]:
        return self.choice.replay_options(lesson, None, None)


class BehaviourRecurrentQ(RecurrentQ):
    """Recurrent-Q over behaviours (Ch. 8, 8.3; see the module docstring): no on-line learning, batch replay."""

    replay_at_most_stored = True  # as BehaviourQCON's; Ch. 8's builder sets it from replay_from_start

    def __init__(self, config: RecurrentQConfig, n_behaviours: int, rng: np.random.Generator,
                 choice: BehaviourChoice | None = None, *, merit_scale: float = 100.0):
        super().__init__(config, n_behaviours, rng, merit_scale=merit_scale)
        self.choice = choice if choice is not None else BehaviourChoice()

    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = True) -> None:
        super().begin_trial(obs, info, trial=trial, learning=learning)
        self.choice.begin_trial(info)

    def act(self, obs, info=None, *, greedy: bool = False) -> int:
        self._x = np.asarray(obs, dtype=np.float64).ravel()
        self.last_q = self.net.values(self._x)  # the probe of Exp. 8 reads it
        b, self.last_probabilities = self.choice.choose(self.last_q, info, self.temperature(info, greedy), self.rng)
        self.net.advance(b)  # the chosen behaviour's net makes the next context (7.4)
        return b

    def observe(self, action, reward, next_obs, terminated, truncated, info=None) -> None:
        self.choice.observed(info)
        super().observe(action, reward, next_obs, terminated, truncated, info)

    def end_trial(self) -> Lesson | None:
        lesson = super().end_trial()
        self.choice.file(lesson)
        return lesson

    def replay_lesson(self, lesson: Lesson, p_threshold: float, weights=None, allowed=None) -> None:
        w, ok = self.choice.replay_options(lesson, weights, allowed)
        replay_recurrent_q(self.net, lesson, self.replay_params(p_threshold), w, ok)

    one_call_reproduces = (replay_lesson,)  # replay_lessons' one call does its work

    def lesson_options(self, lesson: Lesson) -> tuple[np.ndarray | None, np.ndarray | None]:
        return self.choice.replay_options(lesson, None, None)
