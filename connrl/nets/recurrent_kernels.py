"""The recurrent OAON's Numba kernels (7.4, 7.5): forward passes, BPTT with momentum, and the whole batch replay of a
lesson into a recurrent Q-net. They call one another, so they share this file (a cached kernel may only call its own
file's: tests/nets/test_kernel_cache.py); ``connrl.nets.recurrent`` holds the net that uses them.

The helpers that run per step or per lesson are inlined into their callers (``inline="always"``: a fifth off Ch. 8's
recurrent replay, issue 45). That cannot move a number: these kernels are compiled without fastmath, so LLVM keeps
every operation and its order wherever the code lands.
"""

from __future__ import annotations

import math

import numba
import numpy as np

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
    """The non-policy test (3.5.1) at every step, into ``weights`` (1 replayed, 0 not): the taken action's probability
    by Eq. 3.6, or by Eq. 6.6 with each step's W (``bweights`` (n, A); 0 rows: none), against P_t; greedy ties share
    the mass at T = 0. ``connrl.core.replay.policy_mask``'s arithmetic (its sums run left to right, as NumPy's do
    over fewer than 8 choices)."""
    n_a = ys.shape[1]
    has_w = bweights.shape[0] > 0
    for t in range(actions.shape[0]):
        m, found = 0.0, False
        for b in range(n_a):
            if (not has_w or bweights[t, b] > 0.0) and (not found or ys[t, b, 0] > m):
                m, found = ys[t, b, 0], True
        a = actions[t]
        if temperature == 0.0:
            ties = 0
            for b in range(n_a):
                ties += (not has_w or bweights[t, b] > 0.0) and ys[t, b, 0] == m
            p = 1.0 / ties if ((not has_w or bweights[t, a] > 0.0) and ys[t, a, 0] == m) else 0.0
        else:
            z, ea = 0.0, 0.0
            for b in range(n_a):
                e = 0.0
                if not has_w:
                    e = math.exp((ys[t, b, 0] - m) / temperature)
                elif bweights[t, b] > 0.0:
                    e = bweights[t, b] * math.exp((ys[t, b, 0] - m) / temperature)
                z += e
                if b == a:
                    ea = e
            p = ea / z
        weights[t] = 1.0 if p >= p_threshold else 0.0


@numba.njit(cache=True)
def _replay_q_lesson(w1, w2, d1, d2, g1, g2, xs, actions, rewards, terminated, gamma, lam, temperature,
                     p_threshold, clip, has_clip, feedback, decay, scale, lr, momentum, bweights, allowed):
    """Batch replay of one lesson into a recurrent Q-net, whole (7.5; Fig. 5.1(a) in batch mode): every net's values
    along the lesson from c_0 = 0, the non-policy test (3.5.1, with Eq. 6.6's W per step in ``bweights`` (n, A)), the
    lambda-returns from those fixed values (Eq. 5.5; each state's max over its ``allowed`` (n+1, A) choices, all where
    none is), then one BPTT + momentum step on the policy steps. 0-row ``bweights`` / ``allowed``: none. The same
    arithmetic as ``connrl.agents.memory``'s ``replay_recurrent_q`` composes from ``batch_targets`` and
    ``train_sequence``; returns the steps replayed. ``xs`` (n+1, I) holds the lesson's inputs, the last one the state
    after the last action."""
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
        lam_t = lam if (t < n - 1 and weights[t + 1] > 0.0) else 0.0  # a non-policy next action cuts lambda
        e = rewards[t] + gamma * ((1.0 - lam_t) * u + lam_t * e_next)
        if has_clip and e > clip:
            e = clip
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
def _replay_q_lessons(w1, w2, d1, d2, g1, g2, inputs, actions, rewards, terminated, in_start, step_start, order,
                      thresholds, gamma, lam, temperature, clip, has_clip, feedback, decay, scale, lr, momentum,
                      bweights, allowed):
    """``_replay_q_lesson`` on lessons ``order[0]``, ``order[1]``, ... in turn, each at its own P_t
    (``thresholds[k]``): the lessons stored end to end as ``connrl.nets.kernels._replay_q_lessons`` takes them
    (lesson i's steps at rows ``step_start[i]..step_start[i+1]``, its states from row ``in_start[i]``). One call
    for a trial's replays (issue 45)."""
    used = 0
    for k in range(order.shape[0]):
        i = order[k]
        s0, s1, x0 = step_start[i], step_start[i + 1], in_start[i]
        x1 = x0 + (s1 - s0) + 1
        w = bweights[s0:s1] if bweights.shape[0] > 0 else bweights
        m = allowed[x0:x1] if allowed.shape[0] > 0 else allowed
        used += _replay_q_lesson(w1, w2, d1, d2, g1, g2, inputs[x0:x1], actions[s0:s1], rewards[s0:s1],
                                 terminated[i], gamma, lam, temperature, thresholds[k], clip, has_clip, feedback,
                                 decay, scale, lr, momentum, w, m)
    return used
