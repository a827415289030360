"""One network for all actions by input rotation: the "global" action representation of thesis 4.2.4.

With a global action representation (north/east/south/west) the survival task is symmetric under quarter
turns, so Lin used ONE network whose single output is the value (Q-net) or merit (policy net) of moving
*north*; the value of moving in direction ``d`` is the same net applied to the input rotated so that ``d``
points north. Whatever is learned for one direction carries over to the other three.

``RotatedNet(config, permutations, rng)`` takes the rotations as index permutations of the input units
(``permutations[a]`` gives, for each input unit of the rotated observation, the unit of the original one it
reads; for the survival task ``connrl.envs.survival.ROTATION_PERMUTATIONS[ACTION_ROTATION[a]]``). It offers
the Q-function interface of ``connrl.core.replay.QFunction`` (``values``, ``value``, ``update``, ``update_error``)
so QCON, AHCON (as the policy net) and the replay loops use it unchanged.

All four action values come from one Numba call that reads the input through the permutations, so no
rotated copies are made on the hot path.
"""

from __future__ import annotations

import numpy as np

from connrl.nets.kernels import _rotated_update, _rotated_values
from connrl.nets.mlp import OAON, NetConfig


class RotatedNet:
    """A single symmetric-sigmoid MLP evaluated on rotated copies of the input, one per action (4.2.4)."""

    def __init__(self, config: NetConfig, permutations: np.ndarray, rng: np.random.Generator):
        perms = np.ascontiguousarray(permutations, dtype=np.int64)
        if perms.ndim != 2 or perms.shape[1] != config.n_inputs:
            raise ValueError(f"permutations must have shape (n_actions, {config.n_inputs}), got {perms.shape}")
        if not all(np.array_equal(np.sort(p), np.arange(config.n_inputs)) for p in perms):
            raise ValueError("each row of permutations must be a permutation of the input units")
        if config.n_hidden < 1:
            raise ValueError("RotatedNet needs a hidden layer (n_hidden >= 1)")
        self.net = OAON(config, 1, rng)  # the weights live in a one-net OAON (same init and persistence)
        self.config = config
        self.perms = perms
        self.n_actions = perms.shape[0]
        self._xr = np.empty(config.n_inputs)

    @property
    def lr(self) -> float:
        return self.net.lr

    @lr.setter
    def lr(self, value: float) -> None:
        self.net.lr = value

    def values(self, x: np.ndarray) -> np.ndarray:
        q = np.empty(self.n_actions)
        _rotated_values(self.net.w1, self.net.w2, np.ascontiguousarray(x, dtype=np.float64), self.perms,
                        self.net.scale, q, self._xr)
        return q

    def value(self, x: np.ndarray, a: int) -> float:
        return self.net.value(np.asarray(x, dtype=np.float64)[self.perms[a]], 0)

    def update(self, x: np.ndarray, a: int, target: float) -> float:
        """Move the value of action ``a`` toward ``target`` (the shared net sees x rotated for ``a``)."""
        return self._step(x, a, float(target), False)

    def update_error(self, x: np.ndarray, a: int, error: float) -> float:
        return self._step(x, a, float(error), True)

    def _step(self, x, a, value, is_error):
        n = self.net
        return _rotated_update(n.w1, n.w2, n.d1, n.d2, np.ascontiguousarray(x, dtype=np.float64), self.perms[a],
                               self._xr, n._h, value, is_error, n.scale, n.lr, self.config.momentum)

    def state_dict(self) -> dict[str, np.ndarray]:
        return self.net.state_dict()

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        self.net.load_state_dict(state)
