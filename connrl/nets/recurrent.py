"""Recurrent OAON: one modified Elman network per action, sharing context activations (thesis 7.3, 7.4).

Each action net a is a one-hidden-layer symmetric-sigmoid network (``f(x) = 1/(1+e^-x) - 0.5``) whose input
layer is the true input x_t followed by C context units c_t (Fig. 7.3.b). The thesis's three changes to the
Elman network (7.4) are implemented as follows.

- **Only C hidden units are fed back**: the context is a copy of the first C hidden activations.
- **Constant feedback weight w** (1.5): ``c_{t+1} = w * h^{a_t}_{1..C}(t)``; the hidden activations are
  *magnified* ("By magnifying their activations...", 7.4), with no extra squashing. ``c_0 = 0`` at the start
  of every trial ("initialized to 0 at the start of each task instance").
- **BPTT over the whole trial**: the nets are unfolded over the full sequence, errors back-propagated
  through the whole chain and the weights changed once by the cumulative gradient (batch mode, 7.4, 7.5).
  The error reaching the hidden layer at t-1 through the context units at t is multiplied by ``decay``
  (0.9): ``dE/dh_{1..C}(t-1) += decay * w * dE/dc_t``. With ``decay = 1`` this is the exact gradient.

**Whose hidden units become the context.** "At any given time, only the network corresponding to the
selected action is used to compute the next values of the output and context units" (Fig. 7.3, 7.4), and
the nets "share activations of context units": at step t every action net reads the *same* c_t (so the
Q-values of all actions can be compared), and c_{t+1} comes from the net of the action actually taken, a_t.
For a Q-net this means the context is advanced only after the action is chosen (``values`` then
``advance``); an action model, which is given the action, uses ``step``.

**Shared output connections** (``share_output=True``): "having the networks share all connections emitting
from the hidden layer" (7.4). The only connections leaving the hidden layer are hidden->output (the
feedback copy has the constant weight w), so all nets use one hidden->output layer; its bias is treated as a
connection from the hidden layer's always-on bias unit and is shared as well.

**Outputs.** ``n_outputs = 1`` gives recurrent Q-nets (7.3, recurrent-Q); ``n_outputs > 1`` gives the
recurrent action model of the recurrent-model architecture (next sensation + payoff, 7.3). Outputs are
``2 * value_range * f(net)`` and, as in ``connrl.nets.mlp``, errors are divided by ``2 * value_range``
before back-propagation: the loss of a trial is ``0.5 * sum_t weight_t * sum_k ((target - y)/scale)^2`` over
the *taken* action's outputs only (OAON: only the selected net is used at each step).

Weights (float64, C-contiguous), bias in the last column as in ``connrl.nets.mlp``:
``w1[a]`` (H, I + C + 1) is net a's hidden layer over ``[x, c, 1]``; ``w2[s]`` (O, H + 1) its output layer,
with ``s = a``, or ``s = 0`` for every net when ``share_output``. Training is batch momentum SGD:
``d <- momentum * d - lr * grad``; ``w <- w + d`` once per sequence.

The kernels are Numba loops over preallocated arrays (benchmarks/bench_recurrent.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from connrl.core.lessons import pack_lessons
from connrl.nets.kernels import (
    _bptt,
    _forward_all,
    _forward_sequence,
    _momentum_step,
    _replay_recurrent_lesson,
    _replay_recurrent_lessons,
    _train_lessons,
    replay_settings,
)


@dataclass(frozen=True)
class RecurrentNetConfig:
    """Shape and training constants of a recurrent OAON (Table B.1 gives the thesis's values)."""

    n_inputs: int  # true input units (cup task: 4 sensation bits, 6 with random bits; 7.5)
    n_hidden: int  # hidden units H (Table B.1: H_q = 14, H_m = 24 for Task 1)
    n_context: int  # context units C <= H, fed back from the first C hidden units (7.4; C_q = 8, C_m = 16)
    n_outputs: int = 1  # 1 = recurrent Q-net; >1 = recurrent action model: sensation + payoff (7.3)
    value_range: float = 1.0  # outputs span +-value_range (cf. connrl.nets.mlp)
    init_range: float = 0.5  # initial weights uniform in +-init_range (App. B: 0.5)
    output_init: float | None = None  # hidden->output weights in +-output_init (None: init_range); 0 starts
    # every net at the same output, so no action starts below the others (Ch. 6's high level, docs/RECONSTRUCTION.md)
    lr: float = 0.04  # learning rate (Table B.1: eta_q = 0.04 for recurrent-Q, Task 1)
    momentum: float = 0.9  # momentum factor (App. B: 0.9 for multilayer networks)
    feedback: float = 1.5  # constant feedback weight w from hidden to context units (7.4)
    decay: float = 0.9  # error decay on the context path in BPTT (7.4)
    share_output: bool = False  # share hidden->output connections among action nets (7.4: "tends to help")

    def __post_init__(self):
        if self.n_inputs < 1:
            raise ValueError(f"n_inputs must be >= 1, got {self.n_inputs}")
        if self.n_hidden < 1:
            raise ValueError(f"n_hidden must be >= 1 (context units copy hidden units), got {self.n_hidden}")
        if not 0 <= self.n_context <= self.n_hidden:
            raise ValueError(f"n_context must be in [0, n_hidden={self.n_hidden}], got {self.n_context}")
        if self.n_outputs < 1:
            raise ValueError(f"n_outputs must be >= 1, got {self.n_outputs}")
        for name in ("value_range", "init_range"):
            if not 0 < getattr(self, name) < math.inf:
                raise ValueError(f"{name} must be a finite number > 0, got {getattr(self, name)}")
        if self.output_init is not None and not 0 <= self.output_init < math.inf:
            raise ValueError(f"output_init must be None or a finite number >= 0, got {self.output_init}")
        if not 0 < self.lr < math.inf:
            raise ValueError(f"learning rate lr must be a finite number > 0, got {self.lr}")
        if not 0 <= self.momentum < 1:
            raise ValueError(f"momentum must be in [0, 1), got {self.momentum}")
        if not 0 <= self.decay <= 1:
            raise ValueError(f"decay must be in [0, 1] (thesis: 0.9), got {self.decay}")
        if not math.isfinite(self.feedback):
            raise ValueError(f"feedback must be finite (thesis: 1.5), got {self.feedback}")


# --------------------------------------------------------------------------------------- pure functions

def check_sequence(xs, actions, targets, weights, n_inputs, n_actions, n_outputs):
    """A trial's arrays as the kernels take them (contiguous float64 / int64, targets (T, O), weights (T,) >= 0,
    ones if None), or one ValueError naming the one that does not fit."""
    xs = np.ascontiguousarray(xs, dtype=np.float64)
    if xs.ndim != 2 or xs.shape[1] != n_inputs or xs.shape[0] < 1:
        raise ValueError(f"xs must have shape (T >= 1, n_inputs={n_inputs}), got {xs.shape}")
    n_t = xs.shape[0]
    actions = np.ascontiguousarray(actions, dtype=np.int64)
    if actions.shape != (n_t,):
        raise ValueError(f"actions must have shape (T={n_t},), got {actions.shape}")
    if actions.min() < 0 or actions.max() >= n_actions:
        raise ValueError(f"actions must be in [0, {n_actions}), got {actions.min()}..{actions.max()}")
    if targets is not None:
        targets = np.ascontiguousarray(targets, dtype=np.float64)
        if targets.ndim == 1 and n_outputs == 1:
            targets = targets.reshape(-1, 1)
        if targets.shape != (n_t, n_outputs):
            raise ValueError(f"targets must have shape (T={n_t}, n_outputs={n_outputs}), got {targets.shape}")
    if weights is None:
        weights = np.ones(n_t)
    else:
        weights = np.ascontiguousarray(weights, dtype=np.float64)
        if weights.shape != (n_t,) or not np.all(weights >= 0):
            raise ValueError(f"weights must be (T={n_t},) and >= 0 (0 = step not trained), got {weights}")
    return xs, actions, targets, weights


def _check_choices(weights, allowed, n: int, n_a: int) -> tuple[np.ndarray, np.ndarray]:
    """``weights`` (n, A) >= 0, no row all 0, and ``allowed`` (n+1, A) as the kernel takes them (0 rows for none);
    the same refusals as ``connrl.core.replay``'s."""
    if weights is None:
        w = np.zeros((0, n_a))
    else:
        w = np.ascontiguousarray(weights, dtype=np.float64)
        if w.shape != (n, n_a) or (w < 0).any() or not (w > 0).any(axis=1).all():
            raise ValueError(f"weights must be (n, actions) = {(n, n_a)}, >= 0, not all 0 in a row")
    if allowed is None:
        return w, np.zeros((0, n_a), dtype=np.bool_)
    ok = np.ascontiguousarray(allowed, dtype=np.bool_)
    if ok.shape != (n + 1, n_a):
        raise ValueError(f"allowed must be (n+1, actions) = {(n + 1, n_a)}, got {ok.shape}")
    return w, ok


def gradients(
    w1: np.ndarray,
    w2: np.ndarray,
    xs: np.ndarray,
    actions: np.ndarray,
    targets: np.ndarray,
    weights: np.ndarray | None = None,
    *,
    feedback: float = 1.5,
    decay: float = 0.9,
    value_range: float = 1.0,
) -> tuple[float, np.ndarray, np.ndarray]:
    """Loss of one trial (from a zero context) and its BPTT gradients ``(loss, dL/dw1, dL/dw2)``.

    ``loss = 0.5 * sum_t weights_t * sum_k ((targets_tk - y_t,a_t,k) / (2 value_range))^2``. With
    ``decay = 1`` the gradients are exact; ``decay < 1`` scales every error crossing a context link by
    ``decay`` (7.4), so a contribution that crossed n links is scaled by ``decay**n``. Pure: no state.
    """
    w1 = np.ascontiguousarray(w1, dtype=np.float64)
    w2 = np.ascontiguousarray(w2, dtype=np.float64)
    if w1.ndim != 3 or w2.ndim != 3 or w2.shape[2] != w1.shape[1] + 1 or w2.shape[0] not in (1, w1.shape[0]):
        raise ValueError(f"w1 (A, H, I+C+1) and w2 (A or 1, O, H+1) do not fit: {w1.shape}, {w2.shape}")
    n_in = np.asarray(xs).shape[-1]
    if not 0 <= w1.shape[2] - n_in - 1 <= w1.shape[1]:
        raise ValueError(f"w1 {w1.shape} does not fit {n_in} inputs plus 0..H context units")
    xs, actions, targets, weights = check_sequence(
        xs, actions, targets, weights, n_in, w1.shape[0], w2.shape[1])
    g1 = np.zeros_like(w1)
    g2 = np.zeros_like(w2)
    loss = _bptt(w1, w2, xs, actions, targets, weights, float(feedback), float(decay),
                 2.0 * float(value_range), g1, g2)
    return loss, g1, g2


# ------------------------------------------------------------------------------------------ the network

class RecurrentOAON:
    """Recurrent OAON nets (one modified Elman net per action) with shared context activations.

    Online use within a trial::

        net.reset()                      # c = 0 at the start of a trial
        q = net.values(x)                # Q(x, c, a) for all a, at the current context
        net.advance(a)                   # c <- w * first C hidden units of net a
        y = net.step(x, a)               # action model: outputs of all nets, then advance with a

    Batch training on a whole trial (BPTT from a zero context): ``train_sequence(xs, actions, targets)``.
    ``forward_sequence(xs, actions)`` gives every net's outputs along a recorded trial (e.g. for the
    max over actions in TD targets).
    """

    def __init__(self, config: RecurrentNetConfig, n_nets: int, rng: np.random.Generator):
        if n_nets < 1:
            raise ValueError(f"n_nets must be >= 1, got {n_nets}")
        self.config = config
        self.n_nets = n_nets
        c = config
        self.scale = 2.0 * c.value_range
        lo, hi = -c.init_range, c.init_range
        n_out_nets = 1 if c.share_output else n_nets
        self.w1 = rng.uniform(lo, hi, (n_nets, c.n_hidden, c.n_inputs + c.n_context + 1))
        out = c.init_range if c.output_init is None else c.output_init
        self.w2 = rng.uniform(-out, out, (n_out_nets, c.n_outputs, c.n_hidden + 1))
        self.d1 = np.zeros_like(self.w1)
        self.d2 = np.zeros_like(self.w2)
        self._g1 = np.zeros_like(self.w1)
        self._g2 = np.zeros_like(self.w2)
        self.lr = c.lr  # mutable: an experiment may schedule it (7.5.3 suggests decreasing it)
        self.context = np.zeros(c.n_context)
        self._h_all = np.zeros((n_nets, c.n_hidden))
        self._y = np.zeros((n_nets, c.n_outputs))
        self._fresh = False  # True when _h_all holds a forward pass at the current context

    @property
    def kernel_arrays(self) -> tuple:
        """``(w1, w2, d1, d2, g1, g2)``: the arrays the compiled replay reads and writes (g: gradient buffers)."""
        return self.w1, self.w2, self.d1, self.d2, self._g1, self._g2

    @property
    def kernel_settings(self) -> tuple:
        """``(feedback, decay, scale, lr, momentum)`` of the compiled replay's BPTT step."""
        c = self.config
        return c.feedback, c.decay, self.scale, self.lr, c.momentum

    @property
    def play_arrays(self) -> tuple:
        """``(w1, w2, scale, feedback, context, h_all, y)``: what a compiled play reads of the net, and the context
        (and the last forward pass's activations) it moves on."""
        return self.w1, self.w2, self.scale, self.config.feedback, self.context, self._h_all, self._y

    # -- online (one step at a time)
    def reset(self) -> None:
        """Zero the context units (start of a trial, 7.4)."""
        self.context[:] = 0.0
        self._fresh = False

    def outputs(self, x: np.ndarray) -> np.ndarray:
        """(n_nets, n_outputs) outputs of every action net at x and the current context (state unchanged)."""
        x = np.ascontiguousarray(x, dtype=np.float64)
        if x.shape != (self.config.n_inputs,):
            raise ValueError(f"x must have shape ({self.config.n_inputs},), got {x.shape}")
        _forward_all(self.w1, self.w2, x, self.context, self.scale, self._h_all, self._y)
        self._fresh = True
        return self._y.copy()

    def values(self, x: np.ndarray) -> np.ndarray:
        """(n_nets,) Q-values at x and the current context; needs ``n_outputs == 1``."""
        if self.config.n_outputs != 1:
            raise ValueError(f"values() is for Q-nets (n_outputs=1); this net has {self.config.n_outputs}")
        return self.outputs(x)[:, 0]

    def advance(self, action: int) -> None:
        """Move to the next step: context <- feedback * first C hidden units of net ``action``."""
        if not self._fresh:
            raise RuntimeError("advance() needs a preceding outputs()/values() call at the current context")
        if not 0 <= action < self.n_nets:
            raise ValueError(f"action must be in [0, {self.n_nets}), got {action}")
        n_c = self.config.n_context
        self.context[:] = self.config.feedback * self._h_all[action, :n_c]
        self._fresh = False

    def step(self, x: np.ndarray, action: int) -> np.ndarray:
        """``outputs(x)`` then ``advance(action)``: for an action model, which is told the action."""
        y = self.outputs(x)
        self.advance(action)
        return y

    # -- whole trials
    def forward_sequence(self, xs: np.ndarray, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Replay a trial from c_0 = 0 with the current weights.

        Returns ``(ys, cs)``: ys (T, n_nets, n_outputs) outputs of every net, cs (T+1, n_context) the context
        seen at each step (cs[T] is the context after the last action). Online state is not touched.
        """
        c = self.config
        xs, actions, _, _ = check_sequence(xs, actions, None, None, c.n_inputs, self.n_nets, c.n_outputs)
        return self.forward_checked(xs, actions)

    def forward_checked(self, xs: np.ndarray, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``forward_sequence`` on arrays already as ``check_sequence`` returns them (a caller that replays the same
        lesson many times checks it once)."""
        c = self.config
        ys = np.empty((xs.shape[0], self.n_nets, c.n_outputs))
        cs = np.empty((xs.shape[0] + 1, c.n_context))
        _forward_sequence(self.w1, self.w2, xs, actions, c.feedback, self.scale, ys, cs)
        return ys, cs

    def train_sequence(self, xs: np.ndarray, actions: np.ndarray, targets: np.ndarray,
                       weights: np.ndarray | None = None) -> float:
        """One batch BPTT + momentum step on a trial; returns the loss before the step.

        targets (T, n_outputs) (or (T,) for Q-nets) are for the taken actions' outputs; ``weights`` (T,)
        >= 0 scale each step's error (0 = not trained, e.g. a non-policy action that is not replayed).
        """
        c = self.config
        return self.train_checked(*check_sequence(xs, actions, targets, weights, c.n_inputs, self.n_nets, c.n_outputs))

    def train_checked(self, xs: np.ndarray, actions: np.ndarray, targets: np.ndarray, weights: np.ndarray) -> float:
        """``train_sequence`` on arrays already as ``check_sequence`` returns them."""
        c = self.config
        self._g1[...] = 0.0
        self._g2[...] = 0.0
        loss = _bptt(self.w1, self.w2, xs, actions, targets, weights, c.feedback, c.decay, self.scale,
                     self._g1, self._g2)
        _momentum_step(self.w1.reshape(-1), self.d1.reshape(-1), self._g1.reshape(-1), self.lr, c.momentum)
        _momentum_step(self.w2.reshape(-1), self.d2.reshape(-1), self._g2.reshape(-1), self.lr, c.momentum)
        self._fresh = False
        return loss

    def train_lessons(self, packed: tuple, picks: np.ndarray) -> float:
        """``train_checked`` on lessons ``picks`` of ``packed`` in turn, in one compiled call (issue 45); returns the
        summed loss. ``packed``: (xs, actions, targets, weights, starts), arrays as ``check_sequence`` returns them
        laid end to end, lesson i at rows starts[i]:starts[i + 1]."""
        xs, actions, targets, weights, starts = packed
        c = self.config
        n = int(starts[-1]) if starts.size else -1
        if (starts.size < 2 or starts[0] != 0 or (np.diff(starts) < 1).any() or xs.shape[1:] != (c.n_inputs,)
                or targets.shape[1:] != (c.n_outputs,) or min(len(xs), len(actions), len(targets), len(weights)) < n
                or (n and not 0 <= actions[:n].min() <= actions[:n].max() < self.n_nets)):
            raise ValueError(f"packed lessons must be ({c.n_inputs} inputs, actions 0..{self.n_nets - 1}, "
                             f"{c.n_outputs} targets, weights) rows with lesson starts rising from 0")
        picks = np.asarray(picks, dtype=np.int64)
        if picks.size and not (0 <= picks.min() and picks.max() < starts.size - 1):
            raise ValueError(f"picks must be lessons 0..{starts.size - 2}, got {picks.min()}..{picks.max()}")
        self._fresh = False
        return float(_train_lessons(self.w1, self.w2, self.d1, self.d2, self._g1, self._g2, xs, actions, targets,
                                    weights, starts, picks, c.feedback, c.decay, self.scale, self.lr, c.momentum))

    def replay_q_lesson(self, xs: np.ndarray, actions: np.ndarray, rewards: np.ndarray, terminated: bool, *,
                        gamma: float, lam: float, temperature: float, p_threshold: float,
                        clip: float | None = None, weights: np.ndarray | None = None,
                        allowed: np.ndarray | None = None) -> int:
        """Batch replay of one lesson (inputs ``xs`` (n+1, I), n actions and rewards) in one compiled call: the fast
        path of ``connrl.agents.memory.replay_recurrent_q`` (tests/agents/test_memory.py holds them equal).
        ``weights`` (n, A) and ``allowed`` (n+1, A) as ``connrl.core.replay.batch_targets``'s."""
        c = self.config
        if c.n_outputs != 1:
            raise ValueError(f"replay_q_lesson is for Q-nets (n_outputs=1); this net has {c.n_outputs}")
        if temperature < 0:
            raise ValueError(f"temperature must be >= 0, got {temperature}")
        xs = np.ascontiguousarray(xs, dtype=np.float64)
        _, actions, _, _ = check_sequence(xs[:-1], actions, None, None, c.n_inputs, self.n_nets, 1)
        rewards = np.ascontiguousarray(rewards, dtype=np.float64)
        if rewards.shape != actions.shape:
            raise ValueError(f"rewards must have shape {actions.shape}, got {rewards.shape}")
        w, ok = _check_choices(weights, allowed, len(actions), self.n_nets)
        self._fresh = False
        return int(_replay_recurrent_lesson(self.kernel_arrays, self.kernel_settings, xs, actions, rewards,
                                            bool(terminated), float(gamma),
                                            replay_settings(lam, temperature, p_threshold, clip), w, ok))

    def replay_q_lessons(self, lessons: list, thresholds: list[float], options, *, gamma: float, lam: float,
                         temperature: float, clip: float | None = None) -> int:
        """``replay_q_lesson`` on each of ``lessons`` in turn (the same lesson may come again), lesson k at P_t
        ``thresholds[k]`` and with ``options(lesson)`` = its (weights, allowed), in one compiled call (issue 45).
        Each distinct lesson is checked as ``replay_q_lesson`` checks it, once."""
        c = self.config
        if c.n_outputs != 1:
            raise ValueError(f"replay_q_lessons is for Q-nets (n_outputs=1); this net has {c.n_outputs}")
        if temperature < 0:
            raise ValueError(f"temperature must be >= 0, got {temperature}")

        def check(lesson, weights, allowed):
            check_sequence(np.asarray(lesson.inputs)[:-1], lesson.actions, None, None, c.n_inputs, self.n_nets, 1)
            if np.shape(lesson.rewards) != np.shape(lesson.actions):
                raise ValueError(f"rewards must have shape {np.shape(lesson.actions)}, got {np.shape(lesson.rewards)}")
            _check_choices(weights, allowed, len(lesson.actions), self.n_nets)

        if len(lessons) != len(thresholds):
            raise ValueError(f"{len(lessons)} lessons and {len(thresholds)} thresholds")
        if not lessons:
            return 0
        p = pack_lessons(lessons, options, self.n_nets, check)
        self._fresh = False
        return int(_replay_recurrent_lessons(
            self.kernel_arrays, self.kernel_settings, p.inputs, p.actions, p.rewards, p.terminated, p.in_start,
            p.step_start, p.order, np.asarray(thresholds, dtype=np.float64), float(gamma),
            replay_settings(lam, temperature, 0.0, clip), p.weights, p.allowed))

    # -- plain-format persistence (NPZ, no pickle)
    def state_dict(self) -> dict[str, np.ndarray]:
        return {"w1": self.w1.copy(), "w2": self.w2.copy(), "d1": self.d1.copy(), "d2": self.d2.copy()}

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        for k in ("w1", "w2", "d1", "d2"):
            arr = np.asarray(state[k], dtype=np.float64)
            if arr.shape != getattr(self, k).shape:
                raise ValueError(f"{k}: expected shape {getattr(self, k).shape}, got {arr.shape}")
            getattr(self, k)[...] = arr
        self._fresh = False
