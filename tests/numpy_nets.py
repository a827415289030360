"""An independent NumPy copy of an OAON (``connrl.nets.mlp``) for exact-value tests of the learning rules.

Written from the net's definition, not from its kernels: symmetric sigmoid units ``f(s) = 1/(1+e^-s) - 0.5``
(hidden and output), the output scaled by ``scale = 2 * value_range``, the error divided by ``scale`` before
back-propagation, plain backprop (the hidden deltas use the output weights before the step) and momentum
``d <- lr * (-grad) + momentum * d; w <- w + d``. A net whose one hidden layer every action reads (``shared_hidden``)
keeps one ``w1`` row, which every action's step moves.
"""

from __future__ import annotations

import numpy as np


def f(s):
    return 1.0 / (1.0 + np.exp(-s)) - 0.5


class NumpyOAON:
    """A copy of ``net``'s weights and momentum terms (one hidden layer) that learns by the same rule in NumPy."""

    def __init__(self, net):
        assert net.config.n_hidden > 0
        self.w1, self.w2, self.d1, self.d2 = (net.w1.copy(), net.w2.copy(), net.d1.copy(), net.d2.copy())
        self.scale, self.lr, self.momentum = net.scale, net.lr, net.config.momentum
        self.n_actions = self.w2.shape[0]

    def _row(self, a):
        return 0 if self.w1.shape[0] == 1 else a

    def _forward(self, x, a):
        xb = np.append(np.asarray(x, dtype=np.float64), 1.0)
        h = f(self.w1[self._row(a)] @ xb)
        hb = np.append(h, 1.0)
        return xb, h, hb, f(self.w2[a] @ hb)

    def value(self, x, a):
        return self.scale * self._forward(x, a)[3]

    def values(self, x):
        return np.array([self.value(x, a) for a in range(self.n_actions)])

    def update(self, x, a, target):
        return self._step(x, a, target - self.value(x, a))

    def update_error(self, x, a, error):
        return self._step(x, a, error)

    def _step(self, x, a, err):
        xb, h, hb, y = self._forward(x, a)
        delta = err / self.scale * (0.25 - y * y)
        dh = delta * self.w2[a, :-1] * (0.25 - h * h)
        self.d2[a] = self.lr * delta * hb + self.momentum * self.d2[a]
        r = self._row(a)
        self.d1[r] = self.lr * np.outer(dh, xb) + self.momentum * self.d1[r]
        self.w2[a] += self.d2[a]
        self.w1[r] += self.d1[r]
        return self.scale * y

    def assert_same(self, net, tol=1e-12):
        for name in ("w1", "w2", "d1", "d2"):
            np.testing.assert_allclose(getattr(net, name), getattr(self, name), rtol=0, atol=tol, err_msg=name)
