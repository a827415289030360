"""The high-level learner of Ch. 6: Q(state, behaviour) over learned behaviours (6.5), QCON with Eq. 6.6's choice.

On every primitive step it chooses a behaviour b with probability ``W(b) exp(Q(x, b)/T) / sum_k W(b_k) exp(Q(x,
b_k)/T)``. W comes from the environment's ``info["applicable"]`` (6.4.3): 0 for an inapplicable behaviour, 1 otherwise
(Experiment 2), and with ``persistence`` 100 for the behaviour being followed until its own goal is reached or a
behaviour becomes applicable (Experiment 3, 6.5.1; ``info["behaviour_goal"]``). Each step's W is kept with its lesson
so that replay drops the choices Eq. 6.6 then gave less than P_l ("bad behavior choices were not replayed", 6.6).
With ``target_max="applicable"`` the Q target's max (on-line and in replay) ranges over the behaviours applicable in
the next state only, whose nets may never have been trained there otherwise; ``"all"`` takes it over all four.
Temperatures act on Q / ``merit_scale`` (Q in +-100 with the reward of 100), as for Ch. 5's skills.
"""

from __future__ import annotations

import numpy as np

from connrl.agents.qcon import QCON, QCONConfig
from connrl.core.exploration import persistence_weights, weighted_boltzmann_probabilities
from connrl.core.lessons import Lesson
from connrl.core.replay import ReplayParams


class BehaviourQCON(QCON):
    """QCON over behaviours with W(b) of Eq. 6.6 (see the module docstring)."""

    replay_at_most_stored = True  # "approximately 60 lessons" (6.6): fewer while fewer are stored, as in 5.3.5

    def __init__(self, config: QCONConfig, n_behaviours: int, rng: np.random.Generator, *, persistence: bool = False,
                 persist_weight: float = 100.0, merit_scale: float = 100.0, target_max: str = "all"):
        super().__init__(config, n_behaviours, rng)
        if not merit_scale > 0 or not persist_weight > 0:
            raise ValueError(f"merit_scale and persist_weight must be > 0, got {merit_scale}, {persist_weight}")
        if target_max not in TARGET_MAX:
            raise ValueError(f"target_max must be one of {TARGET_MAX}, got {target_max!r}")
        self.target_max = target_max
        self._trial_applicable: list[np.ndarray] = []
        self.persistence, self.persist_weight, self.merit_scale = bool(persistence), float(persist_weight), merit_scale
        self._active: int | None = None
        self._was_applicable: np.ndarray | None = None
        self._w: np.ndarray | None = None
        self._trial_weights: list[np.ndarray] = []

    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = True) -> None:
        super().begin_trial(obs, info, trial=trial, learning=learning)
        self._active, self._was_applicable, self._trial_weights = None, None, []
        self._trial_applicable = [_applicable(info)] if info is not None and "applicable" in info else []

    def weights(self, info: dict) -> np.ndarray:
        """W(b) for the state of ``info`` (applicability, and the persistence rule when on)."""
        applicable = np.asarray(info["applicable"], dtype=bool)
        if not self.persistence:
            return applicable.astype(np.float64)
        return persistence_weights(applicable, self._was_applicable, self._active,
                                   bool(info.get("behaviour_goal", False)), self.persist_weight)

    def act(self, obs, info=None, *, greedy: bool = False) -> int:
        if info is None or "applicable" not in info:
            raise ValueError("BehaviourQCON needs info['applicable'] from a behaviour-level environment "
                             "(connrl.tasks.recharge.BehaviourEnv)")
        if not self.learning or self._x is None:
            self._x = self.encode(obs)
        q = self.q.values(self._x)
        w = self.weights(info)
        t = 0.0 if greedy else self.explore.temperature(info) * self.merit_scale
        p = weighted_boltzmann_probabilities(q, w, t)
        # greedy tests take the first best without drawing, so testing never moves the learner's random stream
        b = int(np.argmax(p)) if t == 0 else int(self.rng.choice(p.size, p=p))
        self._active, self._was_applicable, self._w = b, np.asarray(info["applicable"], dtype=bool), w
        self.last_probabilities = p
        return b

    def observe(self, action, reward, next_obs, terminated, truncated, info=None) -> None:
        if self.target_max == "applicable" and (info is None or "applicable" not in info):
            raise ValueError("target_max='applicable' needs info['applicable'] of the next state from a "
                             "behaviour-level environment (connrl.tasks.recharge.BehaviourEnv)")
        super().observe(action, reward, next_obs, terminated, truncated, info)
        self._trial_weights.append(self._w)
        if info is not None and "applicable" in info:
            self._trial_applicable.append(_applicable(info))

    def next_value(self, y: np.ndarray, info: dict | None) -> float:
        """With ``target_max="applicable"``: the max over the next state's applicable behaviours (all of them when
        none is), the rule replay's ``allowed`` mask applies too."""
        v = self.q.values(y)
        if self.target_max == "all":
            return float(v.max())
        ok = _applicable(info)
        return float(v[ok].max() if ok.any() else v.max())

    def end_trial(self) -> None:
        if not self.learning:
            return super().end_trial()
        lesson = self.book.close_trial()
        if lesson is not None:
            lesson.meta["weights"] = np.array(self._trial_weights)  # W of each step, for the non-policy test
            if len(self._trial_applicable) == len(lesson) + 1:
                lesson.meta["applicable"] = np.array(self._trial_applicable)  # each state's, for the target's max
        return None

    def replay_params(self, p_threshold: float) -> ReplayParams:
        r = self.config.replay
        return ReplayParams(gamma=self.config.gamma, lam=self.config.lam,
                            temperature=self.explore.base * self.merit_scale, p_threshold=p_threshold, batch=r.batch)

    def replay_lesson(self, lesson: Lesson, p_threshold: float, weights=None, allowed=None) -> None:
        """Replay with the W each step was chosen under and (``target_max="applicable"``) each state's applicable
        behaviours, both kept with the lesson; ``weights`` and ``allowed`` come from the lesson, never the caller."""
        if weights is not None or allowed is not None:
            raise ValueError("BehaviourQCON replays the weights and applicability kept with each lesson")
        allowed = lesson.meta.get("applicable") if self.target_max == "applicable" else None
        super().replay_lesson(lesson, p_threshold, lesson.meta.get("weights"), allowed)


TARGET_MAX = ("all", "applicable")


def _applicable(info: dict) -> np.ndarray:
    return np.asarray(info["applicable"], dtype=bool)
