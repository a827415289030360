"""The averaged greedy policy (``AgentOptions.average_steps``).

Per-sample back-propagation with momentum moves the weights after every step and every replayed experience, so the
greedy policy read off them at any one moment is a noisy sample of what replay has learnt: a task solved at one
evaluation is lost at the next (the relapse, docs/notes/relapse-protocol.md). The agent therefore keeps an
exponential moving average of its weights, updated after each learning trial (and its replay) with the weight
``1 - exp(-steps / average_steps)`` for a trial of ``steps`` steps: about the last ``average_steps`` steps' weights,
whatever the trials' lengths. The greedy policy (``evaluate``, ``predict``, the saved agent) acts with the average;
learning and exploration use the live weights, as the thesis's learners do. Chosen by measurement on development
seeds (docs/notes/solve-protocol.md; docs/PERFORMANCE.md, "An averaged greedy policy").
"""

from __future__ import annotations

import math
from contextlib import contextmanager

import numpy as np

PREFIX = "average."  # the average's arrays in agent.npz: "average." + the nets' state_dict key
WEIGHTS = ("w1", "w2")  # what is averaged of each net (its momentum terms are not weights the policy reads)


def _averaged(key: str) -> bool:
    return key.rsplit(".", 1)[-1] in WEIGHTS


class WeightAverage:
    """An exponential moving average, over environment steps, of ``nets``' weights (``state_dict`` /
    ``load_state_dict``: an OAON, a recurrent net, AHCON's pair), starting at their current weights."""

    def __init__(self, nets, steps: int):
        self.nets, self.steps = nets, steps
        self.arrays = {k: a for k, a in nets.state_dict().items() if _averaged(k)}

    def update(self, trial_steps: int) -> None:
        """Move the average towards the live weights after a learning trial of ``trial_steps`` steps."""
        w = 1.0 - math.exp(-trial_steps / self.steps)
        live = self.nets.state_dict()
        for k, a in self.arrays.items():
            a += w * (live[k] - a)

    def scale_outputs(self, ratio: float) -> None:
        """Follow ``connrl.own.value_scale.rescale(keep_q=True)``: the output layers' weights times ``ratio``."""
        for k, a in self.arrays.items():
            if k.endswith("w2"):
                a *= ratio

    @contextmanager
    def acting(self):
        """The nets hold the average inside the block and their own weights again after it (an error included)."""
        live = self.nets.state_dict()
        try:  # the swap itself inside: a Ctrl-C that lands in it still gives the live weights back
            self.nets.load_state_dict({**live, **self.arrays})
            yield
        finally:
            self.nets.load_state_dict(live)

    def state(self) -> dict[str, np.ndarray]:
        """The arrays an agent file holds: ``PREFIX`` + key."""
        return {PREFIX + k: a.copy() for k, a in self.arrays.items()}

    def load(self, state: dict[str, np.ndarray]) -> None:
        """Set from ``state`` (``state()``'s keys, each checked by the file reader)."""
        for k, a in self.arrays.items():
            a[...] = state[PREFIX + k]
