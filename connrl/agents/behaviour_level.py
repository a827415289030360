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
"""

from __future__ import annotations

import numpy as np

from connrl.agents.memory import RecurrentQ, RecurrentQConfig, replay_recurrent_q
from connrl.agents.qcon import QCON, QCONConfig
from connrl.core.exploration import persistence_weights, weighted_boltzmann_probabilities
from connrl.core.lessons import Lesson
from connrl.core.replay import ReplayParams


class _BehaviourChoice:
    """Eq. 6.6's weighted choice among behaviours and what replay keeps of it; the memoryless and the recurrent
    learner share it (placed first among the bases: its methods wrap the learner's own)."""

    replay_at_most_stored = True  # "approximately 60 lessons" (6.6): fewer while fewer are stored, as in 5.3.5

    def __init__(self, config: QCONConfig | RecurrentQConfig, n_behaviours: int, rng: np.random.Generator, *,
                 persistence: bool = False, persist_weight: float = 100.0, merit_scale: float = 100.0,
                 target_max: str = "all"):
        super().__init__(config, n_behaviours, rng)
        if not merit_scale > 0 or not persist_weight > 0:
            raise ValueError(f"merit_scale and persist_weight must be > 0, got {merit_scale}, {persist_weight}")
        if target_max not in TARGET_MAX:
            raise ValueError(f"target_max must be one of {TARGET_MAX}, got {target_max!r}")
        self.target_max = target_max
        self.persistence, self.persist_weight, self.merit_scale = bool(persistence), float(persist_weight), merit_scale
        self._begin_choice(None)

    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = True) -> None:
        super().begin_trial(obs, info, trial=trial, learning=learning)
        self._begin_choice(info)

    def observe(self, action, reward, next_obs, terminated, truncated, info=None) -> None:
        if self.target_max == "applicable" and (info is None or "applicable" not in info):
            raise ValueError("target_max='applicable' needs info['applicable'] of the next state from a "
                             "behaviour-level environment (connrl.tasks.recharge.BehaviourEnv)")
        super().observe(action, reward, next_obs, terminated, truncated, info)
        self._trial_weights.append(self._w)
        if info is not None and "applicable" in info:
            self._trial_applicable.append(_applicable(info))

    def end_trial(self) -> None:
        if not self.learning:
            self.book.recorder.finish(False, False)
            return
        lesson = self.book.close_trial()
        if lesson is not None:
            lesson.meta["weights"] = np.array(self._trial_weights)  # W of each step, for the non-policy test
            if len(self._trial_applicable) == len(lesson) + 1:
                lesson.meta["applicable"] = np.array(self._trial_applicable)  # each state's, for the target's max

    def _begin_choice(self, info) -> None:
        self._active, self._was_applicable, self._w = None, None, None
        self._trial_weights: list[np.ndarray] = []
        self._trial_applicable = [_applicable(info)] if info is not None and "applicable" in info else []

    def weights(self, info: dict) -> np.ndarray:
        """W(b) for the state of ``info`` (applicability, and the persistence rule when on)."""
        applicable = np.asarray(info["applicable"], dtype=bool)
        if not self.persistence:
            return applicable.astype(np.float64)
        return persistence_weights(applicable, self._was_applicable, self._active,
                                   bool(info.get("behaviour_goal", False)), self.persist_weight)

    def _choose(self, q: np.ndarray, info, greedy: bool) -> int:
        if info is None or "applicable" not in info:
            raise ValueError(f"{type(self).__name__} needs info['applicable'] from a behaviour-level environment "
                             "(connrl.tasks.recharge.BehaviourEnv)")
        w = self.weights(info)
        t = 0.0 if greedy else self.explore.temperature(info) * self.merit_scale
        p = weighted_boltzmann_probabilities(q, w, t)
        # greedy tests take the first best without drawing, so testing never moves the learner's random stream
        b = int(np.argmax(p)) if t == 0 else int(self.rng.choice(p.size, p=p))
        self._active, self._was_applicable, self._w = b, np.asarray(info["applicable"], dtype=bool), w
        self.last_probabilities, self.last_q = p, q
        return b

    def _replay_options(self, lesson: Lesson, weights, allowed):
        if weights is not None or allowed is not None:
            raise ValueError("behaviour-level learners replay the weights and applicability kept with each lesson")
        allowed = lesson.meta.get("applicable") if self.target_max == "applicable" else None
        return lesson.meta.get("weights"), allowed


class BehaviourQCON(_BehaviourChoice, QCON):
    """QCON over behaviours with W(b) of Eq. 6.6 (see the module docstring)."""

    def act(self, obs, info=None, *, greedy: bool = False) -> int:
        if not self.learning or self._x is None:
            self._x = self.encode(obs)
        return self._choose(self.q.values(self._x), info, greedy)

    def next_value(self, y: np.ndarray, info: dict | None) -> float:
        """With ``target_max="applicable"``: the max over the next state's applicable behaviours (all of them when
        none is), the rule replay's ``allowed`` mask applies too."""
        v = self.q.values(y)
        if self.target_max == "all":
            return float(v.max())
        ok = _applicable(info)
        return float(v[ok].max() if ok.any() else v.max())

    def replay_params(self, p_threshold: float) -> ReplayParams:
        r = self.config.replay
        return ReplayParams(gamma=self.config.gamma, lam=self.config.lam,
                            temperature=self.explore.base * self.merit_scale, p_threshold=p_threshold, batch=r.batch)

    def replay_lesson(self, lesson: Lesson, p_threshold: float, weights=None, allowed=None) -> None:
        """Replay with the W each step was chosen under and (``target_max="applicable"``) each state's applicable
        behaviours, both kept with the lesson; ``weights`` and ``allowed`` come from the lesson, never the caller."""
        super().replay_lesson(lesson, p_threshold, *self._replay_options(lesson, weights, allowed))


class BehaviourRecurrentQ(_BehaviourChoice, RecurrentQ):
    """Recurrent-Q over behaviours (Ch. 8, 8.3; see the module docstring): no on-line learning, batch replay."""

    def act(self, obs, info=None, *, greedy: bool = False) -> int:
        self._x = np.asarray(obs, dtype=np.float64).ravel()
        b = self._choose(self.net.values(self._x), info, greedy)
        self.net.advance(b)  # the chosen behaviour's net makes the next context (7.4)
        return b

    def replay_params(self, p_threshold: float) -> ReplayParams:
        return ReplayParams(gamma=self.config.gamma, lam=self.config.lam,
                            temperature=self.explore.base * self.merit_scale, p_threshold=p_threshold, batch=True,
                            clip=self.config.target_clip)

    def replay_lesson(self, lesson: Lesson, p_threshold: float, weights=None, allowed=None) -> None:
        w, ok = self._replay_options(lesson, weights, allowed)
        replay_recurrent_q(self.net, lesson, self.replay_params(p_threshold), w, ok)


TARGET_MAX = ("all", "applicable")


def _applicable(info: dict) -> np.ndarray:
    return np.asarray(info["applicable"], dtype=bool)
