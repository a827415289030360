"""Divergence: a run whose network weights stop being finite numbers (or explode) has failed, not slowed down.

Back-propagation with too large a learning rate blows the weights up; with sigmoid outputs the values then
saturate and the run merely *looks* slow. ``network_problem`` finds any network of an agent (every attribute
with a ``state_dict()``: OAON, rotated and recurrent nets) whose weights are non-finite or beyond
``WEIGHT_LIMIT``; ``DivergenceCheck``, the first callback of every thesis run's training loop, checks after every
training trial and stops the run with ``Diverged``, which the runner records as diverged at that trial.
"""

from __future__ import annotations

import numpy as np

from connrl.core.training import Callback

# Full-profile runs of seed 0 stay far below this: max |w| over training 4.1 (pole-full), 14.8 (pole-full-ahc),
# 27.6 (pole-hidden recurrent-model), 6.3 (cup-task1 recurrent-model), 4.6 / 2.5 (survival AHCON-R / QCON-R),
# 3.4 (robot-teaching-dp) and 1.3 (robot-single-layer DK). lr = 1e6 on pole-full puts the weights at 2.5e4
# after one trial, where every unit is saturated and learning has stopped: the run is dead, not slow.
WEIGHT_LIMIT = 1e4


class Diverged(RuntimeError):
    """A run stopped because its networks diverged after training trial ``trial``."""

    def __init__(self, trial: int, reason: str):
        self.trial, self.reason = trial, reason
        super().__init__(f"diverged after trial {trial}: {reason}")


def network_problem(agent, limit: float = WEIGHT_LIMIT) -> str | None:
    """What is wrong with the agent's networks (non-finite or exploding weights), or None."""
    for name, net in vars(agent).items():
        state = getattr(net, "state_dict", None)
        if not callable(state):
            continue
        for key, w in state().items():
            w = np.asarray(w)
            if w.size == 0:
                continue
            if not np.isfinite(w).all():
                return f"non-finite weights in {name}.{key}"
            big = float(np.abs(w).max())
            if big > limit:
                return f"exploding weights in {name}.{key} (|w| up to {big:.3g} > {limit:g})"
    return None


class DivergenceCheck(Callback):
    """Raises ``Diverged`` after the first training trial that leaves ``learner``'s networks diverged."""

    def __init__(self, learner):
        self.learner, self.trials = learner, 0

    def on_trial_end(self, agent, stats):
        self.trials += 1
        problem = network_problem(self.learner)
        if problem:
            raise Diverged(self.trials, problem)
        return True
