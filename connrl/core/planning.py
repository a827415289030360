"""Relaxation planning with an action model: AHCON-M and QCON-M (thesis 3.6, 4.2.5; Figs. 3.5 and 3.6).

An *action model* maps a state and an action to the next state and reinforcement. Planning here is Lin's
*relaxation planning*: from the state actually visited, every *promising* action (probability of being
chosen > 2%, 3.6.1) is simulated one step with the model and the networks are moved toward the one-step
look-ahead values; nothing is planned when only one action is promising. Each simulated action is a
"hypothetical action" (Fig. 4.5 counts them per step).

* :func:`relaxation_q` — Fig. 3.6: ``U'_a = r + gamma max_k Q(y, k)``; Q(x, a) moves toward U'_a, a in S.
* :func:`relaxation_ahc` — Fig. 3.5: ``E_a = r + gamma V(y)``; V(x) moves toward max_a E_a and the policy
  merit of each a in S by ``E_a - mu`` with ``mu`` the probability-weighted mean of the E_a.
* :class:`RelaxationPlanner` — when to plan (promising threshold, no planning in the first plays with a
  learned model, 4.2.5) and bookkeeping of hypothetical actions; QCON/AHCON call it through their
  ``planner`` option (before choosing an action, so the choice benefits from the look-ahead, 3.6.1).

A model offers ``simulate(x, actions) -> [(y, r, terminal), ...]`` for the current state and, if it
learns, ``learn(x, a, r, y, terminated)`` for each real experience. The survival task's models (perfect
and learned, 4.2.5) are in ``connrl.tasks.survival_models``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.core.exploration import boltzmann_probabilities

# ------------------------------------------------------------------------------------ relaxation planning


def _clip(v: float, clip: float | None) -> float:
    return v if clip is None or v <= clip else clip


def relaxation_q(q, x: np.ndarray, actions, outcomes, gamma: float, clip: float | None = None) -> np.ndarray:
    """Fig. 3.6 steps 4-5 for the promising ``actions`` and their simulated ``outcomes`` [(y, r, terminal)].

    Returns the targets ``U'_a`` (truncated at ``clip``, 4.2.4) after moving Q(x, a) toward each.
    """
    targets = np.empty(len(actions))
    for i, (y, r, terminal) in enumerate(outcomes):
        u = 0.0 if terminal else float(q.values(y).max())
        targets[i] = _clip(r + gamma * u, clip)
    for a, target in zip(actions, targets, strict=True):
        q.update(x, int(a), float(target))
    return targets


def relaxation_ahc(v_net, policy_net, x: np.ndarray, probabilities: np.ndarray, actions, outcomes,
                   gamma: float, clip: float | None = None) -> tuple[np.ndarray, float]:
    """Fig. 3.5 steps 4-7. ``probabilities`` are the policy's Boltzmann probabilities of all actions.

    ``mu`` weights the E_a by the probabilities renormalised over the promising set S (the figure's sum
    runs over S only; renormalising keeps mu a mean when some mass lies outside S). Returns (E, mu).
    """
    e = np.empty(len(actions))
    for i, (y, r, terminal) in enumerate(outcomes):
        u = 0.0 if terminal else float(v_net.value(y, 0))
        e[i] = _clip(r + gamma * u, clip)
    p = np.asarray(probabilities, dtype=np.float64)[np.asarray(actions, dtype=np.int64)]
    dot = mass = 0.0  # sum p E / sum p as plain sums: a BLAS dot adds in another order on some CPUs (AVX-512)
    for p_a, e_a in zip(p.tolist(), e.tolist(), strict=True):
        dot, mass = dot + p_a * e_a, mass + p_a
    mu = dot / mass
    v_net.update(x, 0, float(e.max()))  # step 6
    for a, e_a in zip(actions, e, strict=True):  # step 7
        policy_net.update_error(x, int(a), float(e_a - mu))
    return e, mu


@dataclass(frozen=True)
class PlanningConfig:
    """When relaxation planning happens (3.6.1, 4.2.5, 4.2.7)."""

    promising: float = 0.02  # actions with P(a) > this are promising (3.6.1, 4.2.7: 2%)
    start_trial: int = 0  # no planning before this play (4.2.5: 10 with a learned model, 0 with the perfect one)


class RelaxationPlanner:
    """Relaxation planning for QCON (``agent.q``) or AHCON (``agent.v``, ``agent.policy``) with a model.

    Counts hypothetical actions: ``hypothetical`` (this play) and ``steps`` (planning opportunities, i.e.
    learning steps, this play); ``begin_trial`` resets them.
    """

    def __init__(self, model, config: PlanningConfig = PlanningConfig()):
        self.model = model
        self.config = config
        self.hypothetical = 0
        self.steps = 0

    def begin_trial(self) -> None:
        self.hypothetical = 0
        self.steps = 0

    def plan(self, agent, x: np.ndarray, merits: np.ndarray, temperature: float) -> bool:
        """Plan from the current state before the agent chooses; True when the networks were changed."""
        self.steps += 1
        if agent.trial < self.config.start_trial or temperature <= 0:
            return False
        p = boltzmann_probabilities(merits, temperature)
        actions = np.flatnonzero(p > self.config.promising)
        if len(actions) < 2:  # the policy is decisive: no planning (Figs. 3.5/3.6 step 3)
            return False
        outcomes = self.model.simulate(x, actions)
        self.hypothetical += len(actions)
        c = agent.config
        if hasattr(agent, "q"):
            relaxation_q(agent.q, x, actions, outcomes, c.gamma, c.target_clip)
        else:
            relaxation_ahc(agent.v, agent.policy, x, p, actions, outcomes, c.gamma, c.target_clip)
        return True

    def observe(self, x, a, r, y, terminated) -> None:
        learn = getattr(self.model, "learn", None)
        if learn is not None:
            learn(x, a, r, y, terminated)
