"""Exploration: Boltzmann action selection, temperature schedules, and stuck detection.

The thesis selects actions stochastically with ``P(a_i) = exp(m_i/T) / sum_k exp(m_k/T)`` (Eq. 3.4/3.6), with
the temperature annealed over a run. It writes schedules two ways, ``1/T: a -> b`` (Table 4.1, Table B.1) and
``T: a -> b`` (5.3.4); both are linear in the written quantity over the trials of a run. Tests use T = 0,
i.e. greedy selection.

Values marked (R) are reconstructions; docs/RECONSTRUCTION.md, "Learners and protocols", gives each with its reason.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def boltzmann_probabilities(merits: np.ndarray, temperature: float) -> np.ndarray:
    """Eq. 3.4/3.6. ``temperature == 0`` gives the greedy distribution (ties share the mass)."""
    m = np.asarray(merits, dtype=np.float64)
    if temperature < 0:
        raise ValueError(f"temperature must be >= 0, got {temperature}")
    if temperature == 0:
        best = m == m.max()
        return best / best.sum()
    z = (m - m.max()) / temperature  # shift for overflow safety; the distribution is unchanged
    p = np.exp(z)
    return p / p.sum()


def weighted_boltzmann_probabilities(merits: np.ndarray, weights: np.ndarray, temperature: float) -> np.ndarray:
    """Eq. 6.6: ``P(b) = W(b) exp(Q(b)/T) / sum_k W(b_k) exp(Q(b_k)/T)``. A weight of 0 rules a choice out; T = 0
    gives the greedy choice among the allowed ones (ties share the mass, whatever their weights)."""
    m, w = np.asarray(merits, dtype=np.float64), np.asarray(weights, dtype=np.float64)
    allowed = w > 0  # array methods, not np.all / np.any: this runs on every step of Ch. 6 and 8
    if m.shape != w.shape or not (w >= 0).all() or not allowed.any():
        raise ValueError(f"weights must be >= 0, one per choice, not all 0; got {w.tolist()} for {m.size} choices")
    if temperature < 0:
        raise ValueError(f"temperature must be >= 0, got {temperature}")
    top = m[allowed].max()
    if temperature == 0:
        best = allowed & (m == top)
        return best / best.sum()
    p = np.where(allowed, w * np.exp((m - top) / temperature), 0.0)  # shifted by the allowed maximum: no overflow
    return p / p.sum()


def persistence_weights(applicable: np.ndarray, was_applicable: np.ndarray | None, active: int | None,
                        goal_reached: bool, persist: float = 100.0) -> np.ndarray:
    """W(b) of Experiment 3's persistence rule (6.5.1, 6.6.3): 0 for an inapplicable behaviour; ``persist`` (100) for
    the active one while its last reinforcement was not its goal's and no inapplicable behaviour became applicable;
    1 otherwise. With ``active=None`` (the first step) it is Experiment 2's 0/1."""
    app = np.asarray(applicable, dtype=bool)
    w = app.astype(np.float64)
    if active is None or not app[active] or goal_reached:
        return w
    if was_applicable is not None and (app & ~np.asarray(was_applicable, dtype=bool)).any():
        return w  # a significant change: a behaviour became applicable
    w[active] = persist
    return w


def boltzmann_select(merits: np.ndarray, temperature: float, rng: np.random.Generator) -> tuple[int, np.ndarray]:
    """Draw an action from Eq. 3.4/3.6; returns (action, probabilities)."""
    if temperature <= 0:
        p = boltzmann_probabilities(merits, temperature)
        return int(np.argmax(p)), p  # deterministic at test: first of equal maxima
    # Eq. 3.4 as boltzmann_probabilities computes it, with fewer calls: this runs at every training step
    m = merits if type(merits) is np.ndarray and merits.dtype == np.float64 else np.asarray(merits, dtype=np.float64)
    p = np.exp((m - m.max()) / temperature)
    p /= p.sum()
    a = int(p.cumsum().searchsorted(rng.random() * 1.0, side="right"))
    return min(a, p.size - 1), p


@dataclass(frozen=True)
class TemperatureSchedule:
    """Linear annealing over trials, written as the thesis writes it.

    ``kind="inverse"`` interpolates 1/T linearly from ``start`` to ``end`` (Table 4.1, B.1: ``1/T: a -> b``);
    ``kind="direct"`` interpolates T (5.3.4: ``T: 0.05 -> 0.02``). ``over`` is the number of trials of the
    schedule; afterwards the end value holds.
    """

    start: float  # first value of T or 1/T (Table 4.1, Table B.1, 5.3.4)
    end: float  # last value of T or 1/T
    over: int  # trials over which the value moves linearly from start to end
    kind: str = "inverse"  # "inverse" (1/T: a -> b) or "direct" (T: a -> b)

    def __post_init__(self):
        if self.kind not in ("inverse", "direct"):
            raise ValueError(f"kind must be 'inverse' or 'direct', got {self.kind!r}")
        if not (self.start > 0 and self.end > 0):
            raise ValueError(f"schedule values must be > 0, got {self.start} -> {self.end}")
        if self.over < 1:
            raise ValueError(f"over must be >= 1 trial, got {self.over}")

    @classmethod
    def inverse(cls, start: float, end: float, over: int) -> TemperatureSchedule:
        return cls(start, end, over, "inverse")

    @classmethod
    def direct(cls, start: float, end: float, over: int) -> TemperatureSchedule:
        return cls(start, end, over, "direct")

    def __call__(self, trial: int) -> float:
        """Temperature for a (0-based) trial number."""
        frac = min(max(trial, 0) / max(self.over - 1, 1), 1.0)
        v = self.start + (self.end - self.start) * frac
        return 1.0 / v if self.kind == "inverse" else v


@dataclass(frozen=True)
class StuckConfig:
    """Stuck detection (4.2.6, 5.3.4): raise T while the agent stays in a small area without progress.

    The thesis gives no thresholds; these are our reconstruction. The agent's positions (dead reckoning)
    over the last ``window`` steps are checked; if they all lie within ``radius`` of their mean, the
    temperature is multiplied by ``boost`` until the agent leaves the area.
    """

    window: int = 20  # steps of history looked at (R)
    radius: float = 1.5  # area size in the task's position units (R)
    boost: float = 5.0  # temperature multiplier while stuck (R)


class StuckDetector:
    """Tracks dead-reckoned positions within a trial and tells the agent how much to raise T."""

    def __init__(self, config: StuckConfig):
        self.config = config
        self._pos: list[np.ndarray] = []

    def reset(self) -> None:
        self._pos.clear()

    def factor(self, position) -> float:
        """Record the current position and return the temperature multiplier (1 when not stuck)."""
        c = self.config
        self._pos.append(np.asarray(position, dtype=np.float64).ravel())
        if len(self._pos) > c.window:
            self._pos.pop(0)
        if len(self._pos) < c.window:
            return 1.0
        p = np.stack(self._pos)
        spread = np.linalg.norm(p - p.mean(axis=0), axis=1).max()
        return c.boost if spread <= c.radius else 1.0
