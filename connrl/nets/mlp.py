"""Symmetric-sigmoid MLPs and the OAON container (one network per action), with hand-written backprop.

Every unit (hidden and output) uses ``f(x) = 1/(1+e^-x) - 0.5`` (thesis 2.4, 4.2, 7.4), so an output lies in
(-0.5, 0.5); it is scaled by ``2 * value_range`` to cover the task's value range (Ch. 4: +-1, Ch. 5: +-100).
Errors are divided by the same factor before back-propagation, so learning rates mean the same thing
whatever the range. ``n_hidden = 0`` gives a single-layer perceptron (5.4.4, App. B); with ``linear_output`` its
output unit is linear, ``Q = value_range * net``, trained by the delta rule on the error in units of
value_range: 7.4 gives the sigmoid to output units "in the nonlinear case" only, and calls the linear OAON
"single-layer perceptrons".

The thesis trains per sample (one experience at a time), so the work per call is tiny (a 145-30-1 net is
about 9k multiply-adds) and interpreter/dispatch overhead dominates; the kernels are therefore Numba-compiled
loops over preallocated arrays, in ``connrl.nets.kernels`` with every kernel that calls them (see
benchmarks/bench_core.py and docs/PERFORMANCE.md).

Weights of all action nets are stacked: ``w1[a]`` is net a's hidden layer (H, I+1) and ``w2[a]`` its output
layer (H+1,); the last column/entry is the bias. For a perceptron ``w2[a]`` has shape (I+1,) and ``w1`` is
empty. With ``shared_hidden`` every action's output reads one hidden layer, ``w1[0]`` (``w1`` has one row).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from connrl.nets.kernels import (
    _mlp_forward,
    _mlp_update,
    _mlp_values,
    _perceptron_forward,
    _perceptron_update,
    _perceptron_values,
)

MAX_UNITS = 1024  # hidden or context units of one net, wherever one is sized (train, tune, sweep, settings)


def symmetric_sigmoid(x):
    """``f(x) = 1/(1+exp(-x)) - 0.5`` (thesis 2.4): the unit used everywhere in the thesis."""
    return 1.0 / (1.0 + np.exp(-x)) - 0.5


@dataclass(frozen=True)
class NetConfig:
    """Shape and training constants of one family of action networks."""

    n_inputs: int  # input units (e.g. 145 in Ch. 4, 52/36 in Ch. 5)
    n_hidden: int = 30  # hidden units; 0 = single-layer perceptron (5.4.4, App. B)
    value_range: float = 1.0  # outputs span +-value_range (4.2.4: +-1; 5.3.1: +-100)
    init_range: float = 0.1  # initial weights uniform in +-init_range (4.2.7: 0.1; Ch. 5, 7: 0.5)
    output_init: float | None = None  # hidden->output weights in +-output_init (None: init_range); 0 starts
    # every net at the same output, so no action starts below the others (Ch. 6's high level, docs/RECONSTRUCTION.md);
    # a perceptron (n_hidden=0) has no hidden->output layer and ignores it
    lr: float = 0.1  # back-propagation learning rate (Table 4.1, 5.3.3, Table B.1)
    momentum: float = 0.9  # momentum factor (4.2.7, 5.3.3, App. B)
    linear_output: bool = False  # perceptrons only: a linear output unit, Q = value_range * net (7.4, App. B)
    shared_hidden: bool = False  # one hidden layer for every action's output (3.4's multi-output net) instead of
    # one net per action: an update for one action moves the others' values too, the interference 3.4 names

    def __post_init__(self):
        if self.n_inputs < 1:
            raise ValueError(f"n_inputs must be >= 1, got {self.n_inputs}")
        if self.n_hidden < 0:
            raise ValueError(f"n_hidden must be >= 0 (0 = perceptron), got {self.n_hidden}")
        for name in ("value_range", "init_range"):
            if not 0 < getattr(self, name) < math.inf:
                raise ValueError(f"{name} must be a finite number > 0, got {getattr(self, name)}")
        if self.output_init is not None and not 0 <= self.output_init < math.inf:
            raise ValueError(f"output_init must be None or a finite number >= 0, got {self.output_init}")
        if not 0 < self.lr < math.inf:
            raise ValueError(f"learning rate lr must be a finite number > 0, got {self.lr}")
        if not 0 <= self.momentum < 1:
            raise ValueError(f"momentum must be in [0, 1), got {self.momentum}")
        if self.shared_hidden and self.n_hidden == 0:
            raise ValueError("shared_hidden needs a hidden layer (n_hidden >= 1)")
        if self.linear_output and self.n_hidden > 0:
            raise ValueError("linear_output applies to single-layer perceptrons only (n_hidden=0), "
                             f"got n_hidden={self.n_hidden}")


# ------------------------------------------------------------------------------------------------ OAON

class OAON:
    """One network per action (thesis 3.4, 7.4), all evaluated in one call; with ``shared_hidden``, one network
    whose hidden layer every action's output reads (``w1`` then has one row: ``w1[0]``).

    ``values(x)`` returns the (n_nets,) outputs; ``update(x, a, target)`` back-propagates
    ``target - output_a`` through net a only (Fig. 3.4 step 5) with momentum, and returns the output
    before the step. A single net (``n_nets=1``) is the V-net of AHCON or a Ch. 4 "global" Q-net.
    """

    def __init__(self, config: NetConfig, n_nets: int, rng: np.random.Generator):
        if n_nets < 1:
            raise ValueError(f"n_nets must be >= 1, got {n_nets}")
        self.config = config
        self.n_nets = n_nets
        self.n_actions = n_nets  # as a Q-function (connrl.core.replay.QFunction): one net per action
        c = config
        self.scale = 2.0 * c.value_range
        lo, hi = -c.init_range, c.init_range
        if c.n_hidden > 0:
            self.w1 = rng.uniform(lo, hi, (1 if c.shared_hidden else n_nets, c.n_hidden, c.n_inputs + 1))
            out = c.init_range if c.output_init is None else c.output_init
            self.w2 = rng.uniform(-out, out, (n_nets, c.n_hidden + 1))
        else:
            self.w1 = np.zeros((n_nets, 0, c.n_inputs + 1))
            self.w2 = rng.uniform(lo, hi, (n_nets, c.n_inputs + 1))
        self.d1 = np.zeros_like(self.w1)
        self.d2 = np.zeros_like(self.w2)
        self._h = np.zeros(max(c.n_hidden, 1))
        self.lr = c.lr  # mutable: an experiment may rescale it (Study 2 doubles it)

    @property
    def kernel_arrays(self) -> tuple:
        """``(w1, w2, d1, d2, h)``: the arrays a compiled kernel reads and writes (``connrl.nets.kernels``)."""
        return self.w1, self.w2, self.d1, self.d2, self._h

    @property
    def kernel_settings(self) -> tuple:
        """``(scale, lr, momentum, linear)``: how a compiled kernel scales and steps them."""
        return self.scale, self.lr, self.config.momentum, self.config.linear_output

    def values(self, x: np.ndarray) -> np.ndarray:
        q = np.empty(self.n_nets)
        x = self._checked(x, 0)
        if self.config.n_hidden > 0:
            _mlp_values(self.w1, self.w2, x, self._h, self.scale, q)
        else:
            _perceptron_values(self.w2, x, self.scale, q, self.config.linear_output)
        return q

    def value(self, x: np.ndarray, a: int) -> float:
        x = self._checked(x, a)
        if self.config.n_hidden > 0:
            return self.scale * _mlp_forward(self.w1, self.w2, a, x, self._h)
        return self.scale * _perceptron_forward(self.w2, a, x, self.config.linear_output)

    def update(self, x: np.ndarray, a: int, target: float) -> float:
        """Back-propagate ``target - output_a`` through net a; returns output_a before the step."""
        return self._step(x, a, float(target), False)

    def update_error(self, x: np.ndarray, a: int, error: float) -> float:
        """Back-propagate a given error through net a (AHCON's policy net, Fig. 3.2 step 6)."""
        return self._step(x, a, float(error), True)

    def _checked(self, x, a) -> np.ndarray:
        """``x`` as the kernels read it, after the checks they do not make (they index without bounds)."""
        x = np.ascontiguousarray(x, dtype=np.float64)
        if not 0 <= a < self.n_nets or x.shape != (self.config.n_inputs,):
            raise ValueError(f"net {a} of {self.n_nets} on an input of shape {x.shape}: the nets are 0.."
                             f"{self.n_nets - 1} on {self.config.n_inputs} inputs")
        return x

    def _step(self, x, a, value, is_error):
        x = self._checked(x, a)
        c = self.config
        if c.n_hidden > 0:
            return _mlp_update(self.w1, self.w2, self.d1, self.d2, a, x, self._h, value, is_error,
                               self.scale, self.lr, c.momentum)
        return _perceptron_update(self.w2, self.d2, a, x, value, is_error, self.scale, self.lr, c.momentum,
                                  c.linear_output)

    def loss_gradients(self, x: np.ndarray, a: int, target: float) -> tuple[np.ndarray, np.ndarray]:
        """Gradients of ``0.5 * ((target - y_a) / scale)^2`` w.r.t. (net a's hidden layer, w2[a]) (NumPy; for
        tests); for a linear perceptron, of ``0.5 * ((target - y_a) / value_range)^2`` (the delta rule)."""
        x = np.asarray(x, dtype=np.float64)
        if self.config.n_hidden == 0:
            xb = np.append(x, 1.0)
            if self.config.linear_output:
                r = self.config.value_range
                return np.zeros((0, xb.size)), -(target - r * (self.w2[a] @ xb)) / r * xb
            y = symmetric_sigmoid(self.w2[a] @ xb)
            delta = (target - self.scale * y) / self.scale * (0.25 - y * y)
            return np.zeros((0, xb.size)), -delta * xb
        xb = np.append(x, 1.0)
        h = symmetric_sigmoid(self.w1[0 if self.config.shared_hidden else a] @ xb)
        hb = np.append(h, 1.0)
        y = symmetric_sigmoid(self.w2[a] @ hb)
        delta = (target - self.scale * y) / self.scale * (0.25 - y * y)
        dh = delta * self.w2[a, :-1] * (0.25 - h * h)
        return -np.outer(dh, xb), -delta * hb

    # -- plain-format persistence (NPZ, no pickle)
    def state_dict(self) -> dict[str, np.ndarray]:
        return {"w1": self.w1.copy(), "w2": self.w2.copy(), "d1": self.d1.copy(), "d2": self.d2.copy()}

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        for k in ("w1", "w2", "d1", "d2"):
            arr = np.asarray(state[k], dtype=np.float64)
            if arr.shape != getattr(self, k).shape:
                raise ValueError(f"{k}: expected shape {getattr(self, k).shape}, got {arr.shape}")
            getattr(self, k)[...] = arr
