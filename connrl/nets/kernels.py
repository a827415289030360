"""Every Numba kernel over the nets' stacked weight arrays, in one file: the forward pass and momentum update of
``connrl.nets.mlp``, the rotated net of ``connrl.nets.rotated``, the recurrent OAON of ``connrl.nets.recurrent``
(forward passes, BPTT, batch replay) and the whole-lesson backward replays (Fig. 5.1) that ``connrl.core.replay_kernel``
and the recurrent net run. Fig. 5.1's step 4, the lambda-return, is written here once for each of its two roundings:
``_lambda_target`` (``connrl.core.returns.td_lambda_target`` compiled, to the bit) for the kernels compiled without
fastmath, ``_lambda_target_fused`` (the same expression compiled with fastmath, as the OAON replay has always computed
it) for the OAON replay; no replay writes the recursion itself (tests/nets/test_lambda_step.py).

They share one file because they call one another and Numba inlines what a kernel calls, while ``cache=True``
keys a compiled kernel on its own source file only: a cached replay kernel in another file went on running the
old net arithmetic after ``mlp.py`` was edited (issue 25). The rule, checked by ``tests/nets/test_kernel_cache.py``:
a cached kernel calls, and reads constants, only from its own file.

Each kernel works on one action net (index a) or loops over all of them; arrays are float64, C-contiguous.
Weights of all action nets are stacked: ``w1[a]`` (H, I+1), ``w2[a]`` (H+1,) (a perceptron: ``w2[a]`` (I+1,),
``w1`` empty); the last column/entry is the bias (see ``connrl.nets.mlp``). A net with one hidden layer shared by
every action (3.4's multi-output alternative to OAON) has a single ``w1[0]`` beside A output rows: ``w1.shape[0] <
w2.shape[0]``, and net a's hidden row is ``_hidden_row(w1, a)``.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

# ----------------------------------------------------------- exact arithmetic the net kernels are built from

@intrinsic
def _fma(typingctx, a, b, c):
    """``a * b + c`` rounded once (what fastmath's contraction made of ``c += a * b``)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        return builder.call(builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d])), args)

    return sig, codegen


def _dot_kernel(width: int):
    """An intrinsic ``dot(w, wo, x, xo, n, start)``: ``start + sum_i w[wo + i] x[xo + i]`` over ``n`` entries of two
    C-contiguous float64 arrays of any shape (read flat from the offsets; unchecked), summed as LLVM's AVX-512 loop
    sums it under fastmath: four 8-lane accumulators of fused multiply-adds over blocks of 32 (``start`` in lane 0),
    added (0 + 1) + (2 + 3) and then lane halves (4, 2, 1); one ``width``-lane accumulator over the blocks of
    ``width`` left (the sum so far in lane 0), added the same way; fused multiply-adds over the last few. Written
    here in vector IR, it is that order on every CPU (issue 45), as long as the caller is compiled without fastmath
    (a fastmath caller's flags could reach the inlined code). The offsets spare a kernel the row views, each
    reference-counted."""

    def dot(typingctx, w, wo, x, xo, n, start):
        for arr in (w, x):  # read in a straight line: C-contiguous float64 only (else a typing error)
            if not (isinstance(arr, types.Array) and arr.layout == "C" and arr.dtype == types.float64):
                return None

        def codegen(context, builder, signature, args):
            wp = builder.gep(context.make_array(signature.args[0])(context, builder, args[0]).data, [args[1]])
            xp = builder.gep(context.make_array(signature.args[2])(context, builder, args[2]).data, [args[3]])
            return _DotIR(builder, wp, xp, args[5]).emit(args[4], width)

        return types.float64(w, types.int64, x, types.int64, types.int64, types.float64), codegen

    return intrinsic(dot)


class _DotIR:
    """The IR of ``_dot_kernel``'s sum: the running sum ``s`` and position ``i`` live in stack slots."""

    def __init__(self, builder, wp, xp, start):
        self.b, self.wp, self.xp = builder, wp, xp
        self.d, self.i64 = ir.DoubleType(), ir.IntType(64)
        self.s = cgutils.alloca_once_value(builder, start)
        self.i = cgutils.alloca_once_value(builder, ir.Constant(self.i64, 0))

    def emit(self, n, width: int):
        b, i64 = self.b, self.i64
        with b.if_then(b.icmp_signed(">=", n, ir.Constant(i64, 32))):
            self.blocks(4, 8, b.and_(n, ir.Constant(i64, ~31)))
        rest = b.and_(b.sub(n, b.load(self.i)), ir.Constant(i64, ~(width - 1)))
        with b.if_then(b.icmp_signed(">", rest, ir.Constant(i64, 0))):
            self.blocks(1, width, b.add(b.load(self.i), rest))
        fma1 = cgutils.get_or_insert_function(b.module, ir.FunctionType(self.d, [self.d] * 3), "llvm.fma.f64")
        with cgutils.for_range_slice(b, b.load(self.i), n, ir.Constant(i64, 1)) as (k, _):
            xk, wk = b.load(b.gep(self.xp, [k])), b.load(b.gep(self.wp, [k]))
            b.store(b.call(fma1, [xk, wk, b.load(self.s)]), self.s)
        return b.load(self.s)

    def blocks(self, count: int, lanes: int, stop):
        """``count`` accumulators of ``lanes`` lanes over blocks from i up to stop, then added into s."""
        b, vec = self.b, ir.VectorType(self.d, lanes)
        fma = cgutils.get_or_insert_function(b.module, ir.FunctionType(vec, [vec] * 3), f"llvm.fma.v{lanes}f64")
        zero = ir.Constant(vec, [0.0] * lanes)
        accs = [cgutils.alloca_once_value(b, zero) for _ in range(count)]
        b.store(b.insert_element(zero, b.load(self.s), ir.Constant(self.i64, 0)), accs[0])
        with cgutils.for_range_slice(b, b.load(self.i), stop, ir.Constant(self.i64, count * lanes)) as (k, _):
            for c, acc in enumerate(accs):
                kc = b.add(k, ir.Constant(self.i64, lanes * c))
                xs, ws = (b.load(b.bitcast(b.gep(p, [kc]), vec.as_pointer()), align=8) for p in (self.xp, self.wp))
                b.store(b.call(fma, [xs, ws, b.load(acc)]), acc)
        b.store(stop, self.i)
        vals = [b.load(acc) for acc in accs]
        while len(vals) > 1:
            vals = [b.fadd(vals[k], vals[k + 1]) for k in range(0, len(vals), 2)]
        b.store(self.halves(vals[0], lanes), self.s)

    def halves(self, v, lanes: int):
        """Lanes 0-3 + 4-7 (8 lanes only), then 0-1 + 2-3, then 0 + 1."""
        b = self.b

        def pick(u, idx):
            return b.shuffle_vector(u, u, ir.Constant(ir.VectorType(ir.IntType(32), len(idx)), idx))

        if lanes == 8:
            v = b.fadd(pick(v, [0, 1, 2, 3]), pick(v, [4, 5, 6, 7]))
        v2 = b.fadd(pick(v, [0, 1]), pick(v, [2, 3]))
        return b.fadd(b.extract_element(v2, ir.Constant(self.i64, 0)), b.extract_element(v2, ir.Constant(self.i64, 1)))


# The rotated net's loop (a gathered read of x per input) was planned with 8-lane blocks after the 32s; the hidden
# layer's plain loop in ``_mlp_forward`` with 4-lane ones.
_dot_in_lanes = _dot_kernel(8)
_dot_in_fours = _dot_kernel(4)


# ------------------------------------------------------------------------------- one net: forward and update

@numba.njit(cache=True, inline="always")
def _hidden_row(w1, a):
    """The hidden layer net a reads: its own (OAON), or the one shared by every action (``w1`` with one row)."""
    return a if w1.shape[0] > 1 else 0


@numba.njit(cache=True)
def _forward_at(w1, w2, a, x, xo, h):
    """Forward pass of net a on the input at flat offset ``xo`` of x; fills h (H,) with hidden activations and
    returns the raw output f(net). The arithmetic of the fastmath loop it replaced (issue 45), bit for bit on the
    CPU the stored results were made on (znver5): each hidden sum in ``_dot_in_fours``'s order, the output a chain
    of fused multiply-adds from its bias (tests/nets/test_mlp_kernel.py). Compiled without fastmath, so it is that
    order wherever it is inlined."""
    n_h, n_in1 = w1.shape[1], w1.shape[2]
    n_in = n_in1 - 1
    r = _hidden_row(w1, a)
    row = r * n_h * n_in1
    for j in range(n_h):  # the sums, then the sigmoids (no slower than one loop in the replay)
        h[j] = _dot_in_fours(w1, row + j * n_in1, x, xo, n_in, w1[r, j, n_in])
    for j in range(n_h):
        h[j] = 1.0 / (1.0 + math.exp(-h[j])) - 0.5
    out = w2[a, n_h]
    for j in range(n_h):
        out = _fma(h[j], w2[a, j], out)
    return 1.0 / (1.0 + math.exp(-out)) - 0.5


@numba.njit(cache=True)
def _mlp_forward(w1, w2, a, x, h):
    """Forward pass of net a on x (I,); see ``_forward_at``. For Python: the kernels here call ``_forward_at``
    itself: a call through this one made a small net's forward pass slower than the old fastmath loop (issue 45)."""
    return _forward_at(w1, w2, a, x, 0, h)


@numba.njit(cache=True, fastmath=True)
def _outputs_at(w2, h, y):
    """Every action's raw output from the hidden activations h of a shared hidden layer: a chain of fused
    multiply-adds from its bias, as ``_forward_at``'s (compiled with fastmath like the kernels that call it, so its
    bits do not depend on which of them a process compiled first)."""
    n_h = w2.shape[1] - 1  # not h.size: a caller's scratch may be longer than the layer
    for a in range(w2.shape[0]):
        out = w2[a, n_h]
        for j in range(n_h):
            out = _fma(h[j], w2[a, j], out)
        y[a] = 1.0 / (1.0 + math.exp(-out)) - 0.5


@numba.njit(cache=True, fastmath=True)
def _mlp_values(w1, w2, x, h, scale, q):
    if w1.shape[0] < w2.shape[0]:  # one hidden layer for all: its sums once
        _forward_at(w1, w2, 0, x, 0, h)
        _outputs_at(w2, h, q)
        for a in range(q.size):
            q[a] *= scale
        return
    for a in range(w1.shape[0]):
        q[a] = scale * _forward_at(w1, w2, a, x, 0, h)


@numba.njit(cache=True, fastmath=True)
def _backward_at(w1, w2, d1, d2, a, x, xo, h, y, target, is_error, scale, lr, momentum):
    """The momentum-SGD step of ``_mlp_update`` after its forward pass (output y, hidden activations h, input at
    flat offset ``xo`` of x): a replay that has just run that pass for the policy test need not run it again."""
    n_h, n_in1 = w1.shape[1], w1.shape[2]
    n_in = n_in1 - 1
    r = _hidden_row(w1, a)
    err = target if is_error else target - scale * y
    # error in the net's own output units (see module docstring), times f'(net) = 0.25 - f^2
    delta = err / scale * (0.25 - y * y)
    for j in range(n_h):
        # hidden delta uses the output weight before it is changed (plain backprop)
        dh = delta * w2[a, j] * (0.25 - h[j] * h[j])
        step = lr * delta * h[j] + momentum * d2[a, j]
        d2[a, j] = step
        w2[a, j] += step
        if dh != 0.0 or momentum != 0.0:
            for i in range(n_in):
                s = lr * dh * x[xo + i] + momentum * d1[r, j, i]
                d1[r, j, i] = s
                w1[r, j, i] += s
            s = lr * dh + momentum * d1[r, j, n_in]
            d1[r, j, n_in] = s
            w1[r, j, n_in] += s
    step = lr * delta + momentum * d2[a, n_h]
    d2[a, n_h] = step
    w2[a, n_h] += step
    return scale * y


@numba.njit(cache=True, fastmath=True)
def _mlp_update(w1, w2, d1, d2, a, x, h, target, is_error, scale, lr, momentum):
    """One momentum-SGD step of net a toward ``target`` (or by the error ``target`` when ``is_error``);
    returns the output before the step."""
    y = _forward_at(w1, w2, a, x, 0, h)
    return _backward_at(w1, w2, d1, d2, a, x, 0, h, y, target, is_error, scale, lr, momentum)


@numba.njit(cache=True, fastmath=True)
def _perceptron_forward(w2, a, x, linear):
    """Output of perceptron a in the net's units (times ``scale`` = the value): f(net), or net / 2 when
    ``linear`` (so the value is value_range * net)."""
    n_in = w2.shape[1] - 1
    s = w2[a, n_in]
    for i in range(n_in):
        s += w2[a, i] * x[i]
    if linear:
        return 0.5 * s
    return 1.0 / (1.0 + math.exp(-s)) - 0.5


@numba.njit(cache=True, fastmath=True)
def _perceptron_values(w2, x, scale, q, linear):
    for a in range(w2.shape[0]):
        q[a] = scale * _perceptron_forward(w2, a, x, linear)


@numba.njit(cache=True, fastmath=True)
def _perceptron_update(w2, d2, a, x, target, is_error, scale, lr, momentum, linear):
    n_in = w2.shape[1] - 1
    y = _perceptron_forward(w2, a, x, linear)
    err = target if is_error else target - scale * y
    # gradient of 0.5 (err / value_range)^2 for a linear unit; error in output units times f' otherwise
    delta = 2.0 * err / scale if linear else err / scale * (0.25 - y * y)
    for i in range(n_in):
        s = lr * delta * x[i] + momentum * d2[a, i]
        d2[a, i] = s
        w2[a, i] += s
    s = lr * delta + momentum * d2[a, n_in]
    d2[a, n_in] = s
    w2[a, n_in] += s
    return scale * y


# ---------------------------------------------------------------------- one net on rotated inputs (4.2.4)

@numba.njit(cache=True)
def _rotated_values(w1, w2, x, perms, scale, q, xr):
    """q[a] = scale * net(x[perms[a]]) for every rotation a (one hidden layer, symmetric sigmoids); ``xr`` (I,) is
    scratch. The arithmetic is the fastmath loop's this replaced (a gathered read of x per input; see
    ``_dot_in_lanes``), bit for bit on the CPU the stored results were made on (znver5), and in that loop's order on
    every CPU: tests/nets/test_rotated_kernel.py."""
    n_h, n_in = w1.shape[1], w1.shape[2] - 1
    for a in range(perms.shape[0]):
        for i in range(n_in):
            xr[i] = x[perms[a, i]]
        out = w2[0, n_h]
        for j in range(n_h):
            s = _dot_in_lanes(w1, j * (n_in + 1), xr, 0, n_in, w1[0, j, n_in])
            out = _fma(w2[0, j], 1.0 / (1.0 + math.exp(-s)) - 0.5, out)
        q[a] = scale * (1.0 / (1.0 + math.exp(-out)) - 0.5)


@numba.njit(cache=True, fastmath=True)
def _rotated_update(w1, w2, d1, d2, x, perm, xr, h, target, is_error, scale, lr, momentum):
    for i in range(perm.shape[0]):
        xr[i] = x[perm[i]]
    return _mlp_update(w1, w2, d1, d2, 0, xr, h, target, is_error, scale, lr, momentum)


# ------------------------------------------------------ whole-lesson backward replay (Fig. 5.1a, incremental)

@numba.njit(cache=True, fastmath=True)
def _values_any(w1, w2, x, h, scale, q, linear):
    if w1.shape[1] > 0:
        _mlp_values(w1, w2, x, h, scale, q)
    else:
        _perceptron_values(w2, x, scale, q, linear)


@numba.njit(cache=True, fastmath=True)
def _value_any(w1, w2, a, x, h, scale, linear):
    """Net a's value: the same arithmetic as entry a of ``_values_any``."""
    if w1.shape[1] > 0:
        return scale * _forward_at(w1, w2, a, x, 0, h)
    return scale * _perceptron_forward(w2, a, x, linear)


@numba.njit(cache=True, inline="always")
def _policy_probability(q, w, row, a, temperature):
    """The probability of choice a that the non-policy test (3.5.1) compares with P_t: Eq. 3.6, or Eq. 6.6 under the
    weights w[row] (``w`` with 0 rows: none; a weight of 0 rules a choice out); greedy among the allowed choices at
    T = 0, ties sharing the mass. Every replay kernel's one Boltzmann probability. Inlined (``inline="always"``), so
    each caller computes it with its own flags: the fastmath OAON replays as they always have, the plain ones in
    ``connrl.core.replay.policy_mask``'s order (sums left to right, as NumPy's over fewer than 8 choices). Rows are
    indexed, not sliced: a view costs a small net's replay more than its sums (issue 45). (The compiled choice,
    which must draw as ``boltzmann_select`` does, has its own with NumPy's exp: ``connrl.core.boltzmann_kernel``.)"""
    weighted = w.shape[0] > 0
    if weighted and w[row, a] <= 0.0:
        return 0.0
    top = q[a]
    for k in range(q.size):
        if (not weighted or w[row, k] > 0.0) and q[k] > top:
            top = q[k]
    if temperature == 0.0:
        if not q[a] >= top:  # below the top, or NaN
            return 0.0
        n = 0
        for k in range(q.size):
            if (not weighted or w[row, k] > 0.0) and q[k] == top:
                n += 1
        return 1.0 / n
    s = 0.0
    for k in range(q.size):
        if not weighted:
            s += math.exp((q[k] - top) / temperature)
        elif w[row, k] > 0.0:
            s += w[row, k] * math.exp((q[k] - top) / temperature)
    e = math.exp((q[a] - top) / temperature)
    return w[row, a] * e / s if weighted else e / s


@numba.njit(cache=True, fastmath=True)
def _allowed_max(q, allowed, row):
    """The largest value among the choices allowed in allowed[row] (all of them when none is allowed)."""
    found, best = False, 0.0  # no infinities: fastmath assumes there are none
    for k in range(q.size):
        if allowed[row, k] and (not found or q[k] > best):
            found, best = True, q[k]
    return best if found else q.max()


@numba.njit(cache=True, fastmath=True)
def _update_any(w1, w2, d1, d2, a, x, h, target, scale, lr, momentum, linear):
    if w1.shape[1] > 0:
        _mlp_update(w1, w2, d1, d2, a, x, h, target, False, scale, lr, momentum)
    else:
        _perceptron_update(w2, d2, a, x, target, False, scale, lr, momentum, linear)


@numba.njit(cache=True, fastmath=True)
def _shared_values_at(w1, w2, x, xo, h, ys, scale, q):
    """A shared hidden layer's values of the input at flat offset ``xo`` of x: the hidden sums once (into h), every
    raw output into ys and its value into q."""
    _forward_at(w1, w2, 0, x, xo, h)
    _outputs_at(w2, h, ys)
    for k in range(q.size):
        q[k] = scale * ys[k]


@numba.njit(cache=True, fastmath=True)
def _replay_mlp(w1, w2, d1, d2, h, q, inputs, actions, rewards, terminated, discounts, lam, temperature,
                p_threshold, clip, has_clip, scale, lr, momentum, weights, allowed):
    """``_replay_q_kernel`` for nets with a hidden layer and no repairs, the same arithmetic with less work: the
    inputs read at row offsets (no views), and the update of the action replayed reusing the forward pass the
    policy test has just run on the same weights (issue 45: less time than the step-by-step loop on Ch. 8's small
    nets, benchmarks/bench_speedups.py)."""
    n, n_in = actions.shape[0], inputs.shape[1]
    x = inputs.reshape(inputs.size)
    shared = w1.shape[0] < w2.shape[0]  # one hidden layer for every action: an update moves every value
    used = 0
    e_next = 0.0
    next_policy = False
    cached = np.empty(q.size)  # the policy test's values of inputs[t], step t-1's next-state values but one
    h_a = np.empty(h.size)  # the replayed action's hidden activations and output in that test
    ys = np.empty(q.size if shared else 0)  # a shared layer's raw outputs
    y_a = 0.0
    changed = -1
    for t in range(n - 1, -1, -1):
        if t == n - 1 and terminated:
            u = 0.0
        else:
            if p_threshold > 0.0 and t < n - 1 and not (shared and changed >= 0):
                for k in range(q.size):
                    q[k] = cached[k]
                if changed >= 0:
                    q[changed] = scale * _forward_at(w1, w2, changed, x, (t + 1) * n_in, h)
            elif shared:
                _shared_values_at(w1, w2, x, (t + 1) * n_in, h, ys, scale, q)
            else:
                for k in range(q.size):
                    q[k] = scale * _forward_at(w1, w2, k, x, (t + 1) * n_in, h)
            u = _allowed_max(q, allowed, t + 1) if allowed.shape[0] > 0 else q.max()
        e = _lambda_target_fused(rewards[t], discounts[t], lam if (t < n - 1 and next_policy) else 0.0, u, e_next,
                                 clip, has_clip)
        a = actions[t]
        changed = -1
        if p_threshold > 0.0 and shared:
            _shared_values_at(w1, w2, x, t * n_in, h_a, ys, scale, q)
            y_a = ys[a]
            for k in range(q.size):
                cached[k] = q[k]
            next_policy = _policy_probability(q, weights, t, a, temperature) >= p_threshold
            if next_policy:
                _backward_at(w1, w2, d1, d2, a, x, t * n_in, h_a, y_a, e, False, scale, lr, momentum)
        elif p_threshold > 0.0:
            for k in range(q.size):
                y = _forward_at(w1, w2, k, x, t * n_in, h)
                q[k] = scale * y
                cached[k] = q[k]
                if k == a:
                    y_a = y
                    for j in range(h.size):
                        h_a[j] = h[j]
            next_policy = _policy_probability(q, weights, t, a, temperature) >= p_threshold
            if next_policy:
                _backward_at(w1, w2, d1, d2, a, x, t * n_in, h_a, y_a, e, False, scale, lr, momentum)
        else:
            next_policy = True
            y = _forward_at(w1, w2, a, x, t * n_in, h)
            _backward_at(w1, w2, d1, d2, a, x, t * n_in, h, y, e, False, scale, lr, momentum)
        if next_policy:
            used += 1
            changed = a
        e_next = e
    return used


@numba.njit(cache=True, fastmath=True)
def _replay_q_kernel(net, hyper, q, inputs, actions, rewards, terminated, discounts, replay, repair, weights, allowed):
    """Fig. 5.1(a) in incremental mode over a whole lesson; same arithmetic as ``replay_q_reference``.

    ``net`` is the OAON's ``(w1, w2, d1, d2, h)`` (``OAON.kernel_arrays``), ``hyper`` its ``(scale, lr, momentum,
    linear)`` (``OAON.kernel_settings``) and ``replay`` the replay's ``(lam, temperature, p_threshold, clip,
    has_clip)`` (``connrl.core.replay.ReplayParams.kernel_settings``).

    ``discounts[t]`` is step t's discount (gamma, or gamma^n for a group of n steps, 6.6.4); ``weights`` (n, A) each
    step's W of Eq. 6.6 for the non-policy test, ``allowed`` (n+1, A) the choices the target's max ranges over in
    each state; an empty array (0 rows) means none (Boltzmann test, max over all).

    ``repair`` (5.4.3, for taught lessons; see ``connrl.core.replay.repair_step``): 0 none; 1 *lower*: every other
    action valued above the taught one is moved toward it; 2 *raise*: the taught action is moved toward the largest
    other value. The check follows the TD update of each experience, with the net as it is then.

    Nets with a hidden layer and no repairs take ``_replay_mlp``, the same arithmetic with less work; the others
    ``_replay_q_steps``.
    """
    w1, w2, d1, d2, h = net
    scale, lr, momentum, linear = hyper
    lam, temperature, p_threshold, clip, has_clip = replay
    if w1.shape[1] > 0 and repair == 0:
        return _replay_mlp(w1, w2, d1, d2, h, q, inputs, actions, rewards, terminated, discounts, lam, temperature,
                           p_threshold, clip, has_clip, scale, lr, momentum, weights, allowed)
    return _replay_q_steps(w1, w2, d1, d2, h, q, inputs, actions, rewards, terminated, discounts, lam, temperature,
                           p_threshold, clip, has_clip, scale, lr, momentum, repair, linear, weights, allowed)


@numba.njit(cache=True, fastmath=True)
def _replay_q_steps(w1, w2, d1, d2, h, q, inputs, actions, rewards, terminated, discounts, lam, temperature,
                    p_threshold, clip, has_clip, scale, lr, momentum, repair, linear, weights, allowed):
    """``_replay_q_kernel`` for any OAON, with the 5.4.3 repairs."""
    n = actions.shape[0]
    used = 0
    e_next = 0.0
    next_policy = False
    # With P_t > 0 the policy test's values of inputs[t] serve as step t-1's next-state values: only the net updated
    # at step t has changed since (``changed``; -1 none, -2 all, after a repair), so only it is computed again.
    cached = np.empty(q.size)
    changed = -1
    for t in range(n - 1, -1, -1):
        if t == n - 1 and terminated:
            u = 0.0
        else:
            if p_threshold > 0.0 and t < n - 1 and changed != -2:
                for k in range(q.size):
                    q[k] = cached[k]
                if changed >= 0:
                    q[changed] = _value_any(w1, w2, changed, inputs[t + 1], h, scale, linear)
            else:
                _values_any(w1, w2, inputs[t + 1], h, scale, q, linear)
            u = _allowed_max(q, allowed, t + 1) if allowed.shape[0] > 0 else q.max()
        e = _lambda_target_fused(rewards[t], discounts[t], lam if (t < n - 1 and next_policy) else 0.0, u, e_next,
                                 clip, has_clip)
        a = actions[t]
        changed = -1
        if p_threshold > 0.0:
            _values_any(w1, w2, inputs[t], h, scale, q, linear)
            for k in range(q.size):
                cached[k] = q[k]
            next_policy = _policy_probability(q, weights, t, a, temperature) >= p_threshold
        else:
            next_policy = True
        if next_policy:
            _update_any(w1, w2, d1, d2, a, inputs[t], h, e, scale, lr, momentum, linear)
            used += 1
            changed = a if w1.shape[0] == w2.shape[0] else -2  # a shared hidden layer moves every value
        if repair != 0:
            changed = -2
            _values_any(w1, w2, inputs[t], h, scale, q, linear)
            qa = q[a]
            if repair == 1:
                for i in range(q.shape[0]):
                    if i != a and q[i] > qa:
                        _update_any(w1, w2, d1, d2, i, inputs[t], h, qa, scale, lr, momentum, linear)
            else:
                found, best = False, 0.0  # no infinities: fastmath assumes there are none
                for i in range(q.shape[0]):
                    if i != a and (not found or q[i] > best):
                        found, best = True, q[i]
                if found and best > qa:
                    _update_any(w1, w2, d1, d2, a, inputs[t], h, best, scale, lr, momentum, linear)
        e_next = e
    return used


@numba.njit(cache=True, inline="always")
def _lesson_rows(k, order, step_start, in_start, thresholds, replay):
    """Where the k-th lesson replayed, ``order[k]``, lies in lessons stored end to end: ``(i, s0, s1, x0, x1)``, its
    steps at rows s0:s1 and its states at x0:x1, and the replay's settings at its own P_t ``thresholds[k]``."""
    i = order[k]
    s0, s1, x0 = step_start[i], step_start[i + 1], in_start[i]
    return (i, s0, s1, x0, x0 + (s1 - s0) + 1), (replay[0], replay[1], thresholds[k], replay[3], replay[4])


@numba.njit(cache=True, inline="always")
def _rows(a, lo, hi):
    """Rows lo:hi of a per-step array, or the 0-row array that stands for none."""
    return a[lo:hi] if a.shape[0] > 0 else a


@numba.njit(cache=True)
def _replay_q_lessons(net, hyper, q, inputs, actions, rewards, terminated, discounts, in_start, step_start, order,
                      thresholds, replay, weights, allowed):
    """``_replay_q_kernel`` on lessons ``order[0]``, ``order[1]``, ... in turn, each at its own P_t
    (``thresholds[k]``, in place of ``replay``'s; no repairs): the lessons stored end to end, lesson i's n_i steps at
    rows ``step_start[i]..step_start[i+1]`` of actions, rewards, discounts and weights and its n_i + 1 states at rows
    ``in_start[i]..`` of inputs and allowed (0-row weights / allowed: none). One call for a trial's replays:
    one call instead of a thousand from Python (issue 45)."""
    used = 0
    for k in range(order.shape[0]):
        (i, s0, s1, x0, x1), at_k = _lesson_rows(k, order, step_start, in_start, thresholds, replay)
        used += _replay_q_kernel(net, hyper, q, inputs[x0:x1], actions[s0:s1], rewards[s0:s1], terminated[i],
                                 discounts[s0:s1], at_k, 0, _rows(weights, s0, s1), _rows(allowed, x0, x1))
    return used


# ------------------------------------------ whole-lesson backward replay into a rotated net (4.2.4, Fig. 5.1a)

def replay_settings(lam, temperature, p_threshold, clip) -> tuple:
    """``(lam, temperature, p_threshold, clip, has_clip)``: a replay's settings as the compiled replays take them
    (gamma goes per step, in the discounts)."""
    return float(lam), float(temperature), float(p_threshold), 0.0 if clip is None else float(clip), clip is not None


@numba.njit(cache=True, inline="always")
def _lambda_target(reward, discount, lam_t, u, e_next, clip, has_clip):
    """Eq. 5.5 / Fig. 5.1 step 4 as ``connrl.core.returns.td_lambda_target`` computes it, truncated at ``clip``.
    Inlined into, and called only from, kernels compiled without fastmath: Numba compiles a plain kernel first called
    from a fastmath one with the caller's flags, so its bits would depend on which kernel a process compiled first
    (issue 46; tests/nets/test_lambda_step.py)."""
    e = reward + discount * ((1.0 - lam_t) * u + lam_t * e_next)
    return clip if has_clip and e > clip else e


@numba.njit(cache=True, fastmath=True, inline="always")
def _lambda_target_fused(reward, discount, lam_t, u, e_next, clip, has_clip):
    """Eq. 5.5 as the OAON replay (compiled with fastmath) has always computed it, and its stored results hold:
    ``_lambda_target``'s expression compiled with fastmath, which LLVM rewrites ``u + lam (e' - u)`` and turns, with
    the discounted sum, into two fused multiply-adds (two roundings fewer; equal to the plain step to within an ulp or
    two; tests/nets/test_lambda_step.py holds it to that form). Inlined into its callers (``inline="always"``: a
    called step cost the small nets' replay 3%), which are all compiled with fastmath."""
    e = reward + discount * ((1.0 - lam_t) * u + lam_t * e_next)
    return clip if has_clip and e > clip else e


@numba.njit(cache=True)
def _rotated_policy_test(w1, w2, x, perms, scale, q, xr, a, temperature, p_threshold, no_weights):
    """3.5.1: is ``a`` a policy action at x (always, with P_t = 0)? ``no_weights``: a 0-row array (Eq. 3.6)."""
    if p_threshold <= 0.0:
        return True
    _rotated_values(w1, w2, x, perms, scale, q, xr)
    return _policy_probability(q, no_weights, 0, a, temperature) >= p_threshold


@numba.njit(cache=True)
def _replay_rotated_kernel(net, hyper, xr, q, perms, inputs, actions, rewards, terminated, discounts, replay):
    """Fig. 5.1(a) in incremental mode over a whole lesson into a rotated net: ``replay_q_reference``'s loop step
    for step (its TD arithmetic compiled without fastmath, so the targets are Python's to the bit; the net's own
    kernels are those ``RotatedNet`` calls). ``net``, ``hyper`` (without ``linear``) and ``replay`` as
    ``_replay_q_kernel``'s."""
    w1, w2, d1, d2, h = net
    scale, lr, momentum = hyper
    lam, temperature, p_threshold, clip, has_clip = replay
    n = actions.shape[0]
    used = 0
    e_next = 0.0
    next_policy = False
    no_weights = np.empty((0, q.size))
    for t in range(n - 1, -1, -1):
        u = 0.0
        if not (t == n - 1 and terminated):
            _rotated_values(w1, w2, inputs[t + 1], perms, scale, q, xr)
            u = q[0]
            for k in range(1, q.size):
                u = max(u, q[k])
        e = _lambda_target(rewards[t], discounts[t], lam if (t < n - 1 and next_policy) else 0.0, u, e_next, clip,
                           has_clip)
        a = actions[t]
        next_policy = _rotated_policy_test(w1, w2, inputs[t], perms, scale, q, xr, a, temperature, p_threshold,
                                           no_weights)
        if next_policy:
            _rotated_update(w1, w2, d1, d2, inputs[t], perms[a], xr, h, e, False, scale, lr, momentum)
            used += 1
        e_next = e
    return used


@numba.njit(cache=True)
def _replay_ahc_rotated_kernel(v_net, v_hyper, p_net, p_hyper, xr, q, perms, inputs, actions, rewards, terminated,
                               gamma, replay):
    """Fig. 5.1(b) in incremental mode over a whole lesson: a V-net (one hidden layer) and a rotated policy net,
    ``replay_ahc_reference``'s loop step for step (TD arithmetic without fastmath: Python's to the bit). The V-net's
    and the policy net's arrays and ``(scale, lr, momentum)``, and ``replay``, as ``_replay_rotated_kernel``'s."""
    vw1, vw2, vd1, vd2, vh = v_net
    v_scale, v_lr, v_momentum = v_hyper
    pw1, pw2, pd1, pd2, ph = p_net
    p_scale, p_lr, p_momentum = p_hyper
    lam, temperature, p_threshold, clip, has_clip = replay
    n = actions.shape[0]
    used = 0
    e_next = 0.0
    next_policy = False
    no_weights = np.empty((0, q.size))
    for t in range(n - 1, -1, -1):
        u = 0.0
        if not (t == n - 1 and terminated):
            u = v_scale * _forward_at(vw1, vw2, 0, inputs[t + 1], 0, vh)
        e = _lambda_target(rewards[t], gamma, lam if (t < n - 1 and next_policy) else 0.0, u, e_next, clip, has_clip)
        a = actions[t]
        next_policy = _rotated_policy_test(pw1, pw2, inputs[t], perms, p_scale, q, xr, a, temperature, p_threshold,
                                           no_weights)
        if next_policy:
            v_before = _mlp_update(vw1, vw2, vd1, vd2, 0, inputs[t], vh, e, False, v_scale, v_lr, v_momentum)
            _rotated_update(pw1, pw2, pd1, pd2, inputs[t], perms[a], xr, ph, e - v_before, True, p_scale, p_lr,
                            p_momentum)
            used += 1
        e_next = e
    return used


# ------------------------------------------ the recurrent OAON (7.4, 7.5): forward passes, BPTT, batch replay
# The helpers that run per step or per lesson are inlined into their callers (``inline="always"``: a fifth off Ch. 8's
# recurrent replay, issue 45). That cannot move a number: these kernels are compiled without fastmath, so LLVM keeps
# every operation and its order wherever the code lands.
# --------------------------------------------------------------------------------------------- kernels
# float64, C-contiguous arrays. w1: (A, H, I+C+1) over [x, c, 1]; w2: (S, O, H+1), S = 1 (shared) or A.

@numba.njit(cache=True)
def _hidden(w1, a, x, c, h):
    """Hidden activations of net a at input x and context c, written into h (H,)."""
    n_h = w1.shape[1]
    n_in = x.shape[0]
    n_c = c.shape[0]
    bias = n_in + n_c
    for j in range(n_h):
        s = w1[a, j, bias]
        for i in range(n_in):
            s += w1[a, j, i] * x[i]
        for k in range(n_c):
            s += w1[a, j, n_in + k] * c[k]
        h[j] = 1.0 / (1.0 + math.exp(-s)) - 0.5


@numba.njit(cache=True)
def _output(w2, s, h, o):
    """Squashed outputs f(net) (before scaling) of output layer s, written into o (O,)."""
    n_o, n_h1 = w2.shape[1], w2.shape[2]
    n_h = n_h1 - 1
    for k in range(n_o):
        z = w2[s, k, n_h]
        for j in range(n_h):
            z += w2[s, k, j] * h[j]
        o[k] = 1.0 / (1.0 + math.exp(-z)) - 0.5


@numba.njit(cache=True, inline="always")
def _transposed(w1):
    """w1 (A, H, I+C+1) as (I+C+1, A*H): a row per input (x, c, then the bias), every net's hidden units side by
    side, so that ``_hidden_lanes`` reads each input's weights to many units at once."""
    n_a, n_h, n_w = w1.shape
    wt = np.empty((n_w, n_a * n_h))
    for a in range(n_a):
        for j in range(n_h):
            for i in range(n_w):
                wt[i, a * n_h + j] = w1[a, j, i]
    return wt


@numba.njit(cache=True, inline="always")
def _hidden_lanes(wt, lo, hi, x, c, h):
    """``_hidden``'s sums, not yet squashed (``_squash_output`` does that), for the hidden units lo..hi-1 of
    ``_transposed``'s columns (net a's are a*H..a*H+H-1), into h (hi - lo,). Each unit sums its bias, inputs, then
    context in ``_hidden``'s order, so its value is ``_hidden``'s bit for bit; the units advance together one input
    at a time, which the CPU does in vector lanes."""
    n_in, n_c = x.shape[0], c.shape[0]
    bias = n_in + n_c
    for u in range(lo, hi):
        h[u - lo] = wt[bias, u]
    for i in range(n_in):
        xi = x[i]
        for u in range(lo, hi):
            h[u - lo] += wt[i, u] * xi
    for k in range(n_c):
        ck = c[k]
        for u in range(lo, hi):
            h[u - lo] += wt[n_in + k, u] * ck


@numba.njit(cache=True, inline="always")
def _squash_output(w2, s, h, o):
    """Squash ``_hidden_lanes``' sums h (H,) in place into ``_hidden``'s activations, then ``_output``. Each unit is
    squashed inside the output's chain of additions, a loop the compiler cannot vectorise, so its ``exp`` is libm's
    as in ``_hidden`` (a vectorised exp, e.g. Intel's SVML, would differ in the last bits)."""
    n_h = w2.shape[2] - 1
    for k in range(w2.shape[1]):
        z = w2[s, k, n_h]
        for j in range(n_h):
            if k == 0:
                h[j] = 1.0 / (1.0 + math.exp(-h[j])) - 0.5
            z += w2[s, k, j] * h[j]
        o[k] = 1.0 / (1.0 + math.exp(-z)) - 0.5


@numba.njit(cache=True)
def _forward_all(w1, w2, x, c, scale, h_all, y):
    """Outputs of every action net at (x, c): y (A, O) scaled; h_all (A, H) keeps the hidden layers."""
    n_a = w1.shape[0]
    shared = w2.shape[0] == 1
    for a in range(n_a):
        _hidden(w1, a, x, c, h_all[a])
        _output(w2, 0 if shared else a, h_all[a], y[a])
        for k in range(y.shape[1]):
            y[a, k] *= scale


@numba.njit(cache=True, inline="always")
def _forward_sequence(w1, w2, xs, actions, feedback, scale, ys, cs, hs=None, os=None):
    """Run a trial from c_0 = 0: ys (T, A, O) outputs of all nets, cs (T+1, C) the contexts seen. Given ``hs`` (K, H)
    and ``os`` (K, O), the taken action's hidden layer and output before scaling at the first K steps go there too:
    what ``_bptt``'s own forward pass would compute again."""
    n_t = xs.shape[0]
    n_c = cs.shape[1]
    n_a, n_h = w1.shape[0], w1.shape[1]
    wt = _transposed(w1)
    h_flat = np.empty(n_a * n_h)
    h_all = h_flat.reshape((n_a, n_h))
    shared = w2.shape[0] == 1
    cs[0, :] = 0.0
    for t in range(n_t):
        a = actions[t]
        _hidden_lanes(wt, 0, n_a * n_h, xs[t], cs[t], h_flat)  # every net's hidden sums at once
        for b in range(n_a):  # _forward_all, keeping the taken net's output before it is scaled
            _squash_output(w2, 0 if shared else b, h_all[b], ys[t, b])
            if os is not None and b == a and t < os.shape[0]:
                os[t, :] = ys[t, b, :]
                hs[t, :] = h_all[b, :]
            for k in range(ys.shape[2]):
                ys[t, b, k] *= scale
        for k in range(n_c):
            cs[t + 1, k] = feedback * h_all[a, k]


@numba.njit(cache=True)
def _bptt(w1, w2, xs, actions, targets, weights, feedback, decay, scale, g1, g2):
    """Loss of a trial and its (decayed) BPTT gradients, accumulated into zeroed g1, g2; returns the loss."""
    n_t, n_in = xs.shape
    n_h = w1.shape[1]
    n_c = w1.shape[2] - n_in - 1
    shared = w2.shape[0] == 1
    hs = np.empty((n_t, n_h))
    os = np.empty((n_t, w2.shape[1]))
    cs = np.zeros((n_t + 1, n_c))
    wt = _transposed(w1)
    # forward through the taken actions' nets only (the others do not affect the loss or the context)
    for t in range(n_t):
        a = actions[t]
        _hidden_lanes(wt, a * n_h, a * n_h + n_h, xs[t], cs[t], hs[t])
        _squash_output(w2, 0 if shared else a, hs[t], os[t])
        for k in range(n_c):
            cs[t + 1, k] = feedback * hs[t, k]
    return _bptt_backward(w1, w2, xs, actions, targets, weights, feedback, decay, scale, g1, g2, hs, os, cs)


@numba.njit(cache=True, inline="always")
def _bptt_backward(w1, w2, xs, actions, targets, weights, feedback, decay, scale, g1, g2, hs, os, cs):
    """``_bptt``'s backward pass from the taken actions' hidden layers hs (T, H), raw outputs os (T, O) and contexts
    cs (T+1, C) of its forward pass."""
    n_t, n_in = xs.shape
    n_h = w1.shape[1]
    n_c = w1.shape[2] - n_in - 1
    n_o = w2.shape[1]
    shared = w2.shape[0] == 1
    loss = 0.0
    dc = np.zeros(n_c)  # dE/dc_{t+1}, arriving from step t+1
    dh = np.empty(n_h)
    do = np.empty(n_o)
    for t in range(n_t - 1, -1, -1):
        a = actions[t]
        s = 0 if shared else a
        wt = weights[t]
        for k in range(n_o):
            e = (scale * os[t, k] - targets[t, k]) / scale  # error in the net's own output units
            loss += 0.5 * wt * e * e
            do[k] = wt * e * (0.25 - os[t, k] * os[t, k])  # f'(z) = 0.25 - f^2
        for j in range(n_h):
            dh[j] = 0.0
        for k in range(n_o):
            dk = do[k]
            if dk != 0.0:
                for j in range(n_h):
                    g2[s, k, j] += dk * hs[t, j]
                    dh[j] += dk * w2[s, k, j]
                g2[s, k, n_h] += dk
        for k in range(n_c):  # context path from step t+1, decayed (7.4)
            dh[k] += decay * feedback * dc[k]
        for k in range(n_c):
            dc[k] = 0.0
        for j in range(n_h):
            d = dh[j] * (0.25 - hs[t, j] * hs[t, j])
            if d != 0.0:
                for i in range(n_in):
                    g1[a, j, i] += d * xs[t, i]
                for k in range(n_c):
                    g1[a, j, n_in + k] += d * cs[t, k]
                    dc[k] += d * w1[a, j, n_in + k]
                g1[a, j, n_in + n_c] += d
    return loss


@numba.njit(cache=True)
def _train_lessons(w1, w2, d1, d2, g1, g2, xs, actions, targets, weights, starts, picks, feedback, decay, scale, lr,
                   momentum):
    """One BPTT and momentum step (``RecurrentOAON.train_checked``) on each picked lesson in turn, lesson i being rows
    ``starts[i]:starts[i + 1]`` of the packed arrays; returns the losses summed in order."""
    w1f, w2f, d1f, d2f = w1.reshape(w1.size), w2.reshape(w2.size), d1.reshape(d1.size), d2.reshape(d2.size)
    g1f, g2f = g1.reshape(g1.size), g2.reshape(g2.size)
    loss = 0.0
    for i in picks:
        g1f[:] = 0.0
        g2f[:] = 0.0
        s, e = starts[i], starts[i + 1]
        loss += _bptt(w1, w2, xs[s:e], actions[s:e], targets[s:e], weights[s:e], feedback, decay, scale, g1, g2)
        _momentum_step(w1f, d1f, g1f, lr, momentum)
        _momentum_step(w2f, d2f, g2f, lr, momentum)
    return loss


@numba.njit(cache=True, inline="always")
def _momentum_step(w, d, g, lr, momentum):
    """``d <- momentum * d - lr * g``; ``w <- w + d`` on flat views."""
    for i in range(w.shape[0]):
        step = momentum * d[i] - lr * g[i]
        d[i] = step
        w[i] += step


@numba.njit(cache=True, inline="always")
def _policy_weights(ys, actions, temperature, p_threshold, bweights, weights):
    """The non-policy test (3.5.1) at every step, into ``weights`` (1 replayed, 0 not): the taken action's
    ``_policy_probability`` (Eq. 6.6 with each step's W in ``bweights`` (n, A); 0 rows: Eq. 3.6) against P_t.
    ``connrl.core.replay.policy_mask``'s arithmetic."""
    for t in range(actions.shape[0]):
        p = _policy_probability(ys[t, :, 0], bweights, t, actions[t], temperature)
        weights[t] = 1.0 if p >= p_threshold else 0.0


@numba.njit(cache=True)
def _replay_recurrent_lesson(net, hyper, xs, actions, rewards, terminated, gamma, replay, bweights, allowed):
    """Batch replay of one lesson into a recurrent Q-net, whole (7.5; Fig. 5.1(a) in batch mode): every net's values
    along the lesson from c_0 = 0, the non-policy test (3.5.1, with Eq. 6.6's W per step in ``bweights`` (n, A)), the
    lambda-returns from those fixed values (Eq. 5.5; each state's max over its ``allowed`` (n+1, A) choices, all where
    none is), then one BPTT + momentum step on the policy steps. 0-row ``bweights`` / ``allowed``: none. The same
    arithmetic as ``connrl.agents.memory``'s ``replay_recurrent_q`` composes from ``batch_targets`` and
    ``train_sequence``; returns the steps replayed. ``xs`` (n+1, I) holds the lesson's inputs, the last one the state
    after the last action. ``net`` is ``(w1, w2, d1, d2, g1, g2)`` (``RecurrentOAON.kernel_arrays``: g1, g2 the
    gradient buffers), ``hyper`` ``(feedback, decay, scale, lr, momentum)`` and ``replay`` as ``_replay_q_kernel``'s."""
    w1, w2, d1, d2, g1, g2 = net
    feedback, decay, scale, lr, momentum = hyper
    lam, temperature, p_threshold, clip, has_clip = replay
    n = actions.shape[0]
    n_a = w1.shape[0]
    acts = np.zeros(n + 1, dtype=np.int64)  # the action at x_n does not affect the outputs at x_n
    acts[:n] = actions
    ys = np.empty((n + 1, n_a, 1))
    cs = np.empty((n + 2, w1.shape[2] - xs.shape[1] - 1))  # the contexts of n + 1 steps and the one after
    hs, os = np.empty((n, w1.shape[1])), np.empty((n, 1))  # the taken nets' activations, for the BPTT step
    _forward_sequence(w1, w2, xs, acts, feedback, scale, ys, cs, hs, os)
    weights = np.ones(n)
    if p_threshold > 0.0:
        _policy_weights(ys, actions, temperature, p_threshold, bweights, weights)
    targets = np.empty((n, 1))
    e_next = 0.0
    for t in range(n - 1, -1, -1):
        u = 0.0
        if not (t == n - 1 and terminated):
            some = False
            if allowed.shape[0] > 0:
                for b in range(n_a):
                    some = some or allowed[t + 1, b]
            found = False
            for b in range(n_a):
                if (not some or allowed[t + 1, b]) and (not found or ys[t + 1, b, 0] > u):
                    u, found = ys[t + 1, b, 0], True
        # a non-policy next action cuts lambda
        e = _lambda_target(rewards[t], gamma, lam if (t < n - 1 and weights[t + 1] > 0.0) else 0.0, u, e_next, clip,
                           has_clip)
        targets[t, 0] = e
        e_next = e
    used = 0
    for t in range(n):
        used += weights[t] > 0.0
    if used > 0:
        g1[...] = 0.0
        g2[...] = 0.0
        _bptt_backward(w1, w2, xs[:n], actions, targets, weights, feedback, decay, scale, g1, g2, hs, os, cs[:n + 1])
        _momentum_step(w1.reshape(-1), d1.reshape(-1), g1.reshape(-1), lr, momentum)
        _momentum_step(w2.reshape(-1), d2.reshape(-1), g2.reshape(-1), lr, momentum)
    return used


@numba.njit(cache=True)
def _replay_recurrent_lessons(net, hyper, inputs, actions, rewards, terminated, in_start, step_start, order,
                              thresholds, gamma, replay, bweights, allowed):
    """``_replay_recurrent_lesson`` on lessons ``order[0]``, ``order[1]``, ... in turn, each at its own P_t
    (``thresholds[k]``): the lessons stored end to end as ``_replay_q_lessons`` takes them
    (lesson i's steps at rows ``step_start[i]..step_start[i+1]``, its states from row ``in_start[i]``). One call
    for a trial's replays (issue 45)."""
    used = 0
    for k in range(order.shape[0]):
        (i, s0, s1, x0, x1), at_k = _lesson_rows(k, order, step_start, in_start, thresholds, replay)
        used += _replay_recurrent_lesson(net, hyper, inputs[x0:x1], actions[s0:s1], rewards[s0:s1], terminated[i],
                                         gamma, at_k, _rows(bweights, s0, s1), _rows(allowed, x0, x1))
    return used
