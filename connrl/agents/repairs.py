"""QCON-T for the robot tasks of Ch. 5: fast backward TD(lambda) replay and the *lower* / *raise* repairs (5.4.3).

``TeachingQCON`` is QCON (Fig. 3.4) with experience replay (Fig. 5.1a) and teaching (3.7), plus three things
Ch. 5 needs:

- **Repairs (5.4.3).** Each time a taught lesson is replayed, the agent checks, for every taught experience
  ``(x, a1)``, the condition ``Q(x, a1) >= Q(x, a_i)`` for all ``i`` (Eq. 5.6). On a violation the *lower*
  repair back-propagates ``Q(x, a1) - Q(x, a_i)`` through net ``a_i`` (every violating ``a_i``); the *raise*
  repair back-propagates ``Q(x, a_max) - Q(x, a1)`` through net ``a1``, where ``a_max`` is the most
  over-valued other action. The check is made right after the TD update of that experience (the thesis does
  not say when within the replay; we do it in the same backward pass, with the net as it is then).
- **Temperature on the +-1 scale.** The Boltzmann selector sees ``Q / merit_scale`` (Q / 100 for the robot):
  with Q in +-100 (5.3.1) a temperature of 0.05 (5.3.4) only makes sense relative to +-1, the range Ch. 4
  uses with similar temperatures (Table 4.1). The non-policy test of replay (P_l = 2 %, 5.3.5) uses the same
  probabilities.
- **Speed.** When the Q-function is an :class:`~connrl.nets.OAON`, a whole lesson is replayed by one Numba
  kernel (``connrl.nets.mlp.replay_lesson_q``) that does exactly what :func:`connrl.replay.replay_q` does (incremental
  mode) followed by the repairs; any other Q-function uses ``replay_q`` and :func:`repair_step`.

"Fewer lessons were replayed in the beginning when there were not many lessons available" (5.3.5 fn. 1):
``learn`` replays ``min(lessons_per_trial, lessons in memory)`` experienced lessons.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.agents.qcon import QCON, QCONConfig
from connrl.exploration import boltzmann_select
from connrl.nets import OAON
from connrl.nets.mlp import replay_lesson_q
from connrl.replay import Lesson, ReplayParams, replay_q

REPAIRS = ("none", "lower", "raise")  # 5.4.3; "none" = plain teaching


def repair_step(q, x: np.ndarray, a: int, mode: str) -> int:
    """One 5.4.3 repair of the taught action ``a`` at input ``x`` for any Q-function; returns nets changed.

    ``lower``: every other action valued above ``a`` is moved toward ``Q(x, a)``.
    ``raise``: ``a`` is moved toward the largest other value when that exceeds ``Q(x, a)``.
    """
    if mode not in REPAIRS:
        raise ValueError(f"repair must be one of {REPAIRS}, got {mode!r}")
    if mode == "none":
        return 0
    v = np.asarray(q.values(x), dtype=np.float64)
    others = np.delete(np.arange(v.size), a)
    if mode == "lower":
        changed = 0
        for i in others:
            if v[i] > v[a]:
                q.update(x, int(i), float(v[a]))
                changed += 1
        return changed
    best = int(others[np.argmax(v[others])])
    if v[best] > v[a]:
        q.update(x, a, float(v[best]))
        return 1
    return 0


def replay_oaon(net: OAON, lesson: Lesson, params: ReplayParams, repair: str = "none") -> int:
    """Replay one lesson into an OAON with the kernel (same result as ``replay_q`` + ``repair_step``)."""
    if params.batch:
        raise ValueError("the fast kernel does incremental replay only (5.1.2); use connrl.replay.replay_q")
    return replay_lesson_q(net, lesson.inputs, lesson.actions, lesson.rewards, lesson.terminated, params.gamma,
                           params.lam, params.temperature, params.p_threshold, params.clip, REPAIRS.index(repair))


# ------------------------------------------------------------------------------------------- the agent

@dataclass(frozen=True)
class TeachingConfig:
    """What ``TeachingQCON`` adds to QCONConfig (5.3.4, 5.4.3)."""

    repair: str = "none"  # "none" | "lower" | "raise" repairs on taught lessons (5.4.3)
    merit_scale: float = 100.0  # Boltzmann sees Q / merit_scale: Q in +-100 (5.3.1), T on the +-1 scale (R)
    fast: bool = True  # use the Numba lesson kernel when the Q-function is an OAON

    def __post_init__(self):
        if self.repair not in REPAIRS:
            raise ValueError(f"repair must be one of {REPAIRS}, got {self.repair!r}")
        if not self.merit_scale > 0:
            raise ValueError(f"merit_scale must be > 0, got {self.merit_scale}")


class TeachingQCON(QCON):
    """QCON-T of Ch. 5 with the 5.4.3 repairs; see the module docstring."""

    replay_at_most_stored = True  # 5.3.5 fn. 1

    def __init__(self, config: QCONConfig, n_actions: int, rng: np.random.Generator,
                 teaching: TeachingConfig | None = None, q=None):
        super().__init__(config, n_actions, rng, q=q)
        self.teaching = teaching or TeachingConfig()
        self._fast = self.teaching.fast and isinstance(self.q, OAON) and not (config.replay and config.replay.batch)

    def act(self, obs, info=None, *, greedy: bool = False) -> int:
        if not self.learning or self._x is None:
            self._x = self.encode(obs)
        q = self.q.values(self._x)
        self._q_x = q
        t = 0.0 if greedy else self.explore.temperature(info) * self.teaching.merit_scale
        a, self.last_probabilities = boltzmann_select(q, t, self.rng)
        return a

    def replay_params(self, p_threshold: float) -> ReplayParams:
        p = super().replay_params(p_threshold)
        return ReplayParams(gamma=p.gamma, lam=p.lam, temperature=p.temperature * self.teaching.merit_scale,
                            p_threshold=p.p_threshold, batch=p.batch, clip=p.clip)

    def replay_lesson(self, lesson: Lesson, p_threshold: float) -> None:
        params = self.replay_params(p_threshold)
        repair = self.teaching.repair if lesson.taught else "none"
        if self._fast:
            replay_oaon(self.q, lesson, params, repair)
            return
        if repair == "none":
            replay_q(self.q, lesson, params)
            return
        # the reference path: the same backward pass, with the repair right after each TD update
        _replay_q_with_repairs(self.q, lesson, params, repair)


def _replay_q_with_repairs(q, lesson: Lesson, params: ReplayParams, repair: str) -> int:
    """Pure-Python twin of the compiled replay with repairs (``connrl.nets.mlp.replay_lesson_q``), for
    Q-functions that are not OAONs and for tests."""
    from connrl.exploration import boltzmann_probabilities

    x, acts, rews = lesson.inputs, lesson.actions, lesson.rewards
    n = len(lesson)
    used, e_next, next_policy = 0, 0.0, False
    for t in range(n - 1, -1, -1):
        u = 0.0 if (t == n - 1 and lesson.terminated) else float(q.values(x[t + 1]).max())
        lam_t = params.lam if (t < n - 1 and next_policy) else 0.0
        e = rews[t] + params.gamma * ((1.0 - lam_t) * u + lam_t * e_next)
        if params.clip is not None and e > params.clip:
            e = params.clip
        a = int(acts[t])
        next_policy = params.p_threshold <= 0 or bool(
            boltzmann_probabilities(q.values(x[t]), params.temperature)[a] >= params.p_threshold)
        if next_policy:
            q.update(x[t], a, e)
            used += 1
        repair_step(q, x[t], a, repair)
        e_next = e
    return used
