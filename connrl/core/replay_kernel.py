"""The compiled fast path of Fig. 5.1(a): a whole lesson replayed into an OAON by one Numba kernel.

Per-sample replay of tiny nets is dominated by interpreter overhead, so the incremental backward loop of
``connrl.core.replay.replay_q_reference`` is compiled here over the OAON's stacked weight arrays (see
benchmarks/bench_core.py). ``tests/core/test_replay.py`` checks it against the plain loop.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from connrl.nets.mlp import OAON, _mlp_update, _mlp_values, _perceptron_update, _perceptron_values


@numba.njit(cache=True, fastmath=True)
def _values_any(w1, w2, x, h, scale, q, linear):
    if w1.shape[1] > 0:
        _mlp_values(w1, w2, x, h, scale, q)
    else:
        _perceptron_values(w2, x, scale, q, linear)


@numba.njit(cache=True, fastmath=True)
def _policy_probability(q, a, temperature):
    """Eq. 3.6 probability of action a (greedy, ties shared, at T = 0)."""
    m = q.max()
    if temperature == 0.0:
        if q[a] < m:
            return 0.0
        n = 0
        for k in range(q.size):
            if q[k] == m:
                n += 1
        return 1.0 / n
    s = 0.0
    for k in range(q.size):
        s += math.exp((q[k] - m) / temperature)
    return math.exp((q[a] - m) / temperature) / s


@numba.njit(cache=True, fastmath=True)
def _weighted_policy_probability(q, w, a, temperature):
    """Eq. 6.6 probability of choice a under weights w (0 rules a choice out; greedy among the allowed at T = 0)."""
    if w[a] <= 0.0:
        return 0.0
    top = q[a]  # no infinities: fastmath assumes there are none
    for k in range(q.size):
        if w[k] > 0.0 and q[k] > top:
            top = q[k]
    if temperature == 0.0:
        if q[a] < top:
            return 0.0
        n = 0
        for k in range(q.size):
            if w[k] > 0.0 and q[k] == top:
                n += 1
        return 1.0 / n
    s = 0.0
    for k in range(q.size):
        if w[k] > 0.0:
            s += w[k] * math.exp((q[k] - top) / temperature)
    return w[a] * math.exp((q[a] - top) / temperature) / s


@numba.njit(cache=True, fastmath=True)
def _allowed_max(q, allowed):
    """The largest value among the allowed choices (all of them when none is allowed)."""
    found, best = False, 0.0  # no infinities: fastmath assumes there are none
    for k in range(q.size):
        if allowed[k] and (not found or q[k] > best):
            found, best = True, q[k]
    return best if found else q.max()


@numba.njit(cache=True, fastmath=True)
def _update_any(w1, w2, d1, d2, a, x, h, target, scale, lr, momentum, linear):
    if w1.shape[1] > 0:
        _mlp_update(w1, w2, d1, d2, a, x, h, target, False, scale, lr, momentum)
    else:
        _perceptron_update(w2, d2, a, x, target, False, scale, lr, momentum, linear)


@numba.njit(cache=True, fastmath=True)
def _replay_q_kernel(w1, w2, d1, d2, h, q, inputs, actions, rewards, terminated, discounts, lam, temperature,
                     p_threshold, clip, has_clip, scale, lr, momentum, repair, linear, weights, allowed):
    """Fig. 5.1(a) in incremental mode over a whole lesson; same arithmetic as ``replay_q_reference``.

    ``discounts[t]`` is step t's discount (gamma, or gamma^n for a group of n steps, 6.6.4); ``weights`` (n, A) each
    step's W of Eq. 6.6 for the non-policy test, ``allowed`` (n+1, A) the choices the target's max ranges over in
    each state; an empty array (0 rows) means none (Boltzmann test, max over all).

    ``repair`` (5.4.3, for taught lessons; see ``connrl.core.replay.repair_step``): 0 none; 1 *lower*: every other
    action valued above the taught one is moved toward it; 2 *raise*: the taught action is moved toward the largest
    other value. The check follows the TD update of each experience, with the net as it is then.
    """
    n = actions.shape[0]
    used = 0
    e_next = 0.0
    next_policy = False
    for t in range(n - 1, -1, -1):
        if t == n - 1 and terminated:
            u = 0.0
        else:
            _values_any(w1, w2, inputs[t + 1], h, scale, q, linear)
            u = _allowed_max(q, allowed[t + 1]) if allowed.shape[0] > 0 else q.max()
        lam_t = lam if (t < n - 1 and next_policy) else 0.0
        e = rewards[t] + discounts[t] * ((1.0 - lam_t) * u + lam_t * e_next)
        if has_clip and e > clip:
            e = clip
        a = actions[t]
        if p_threshold > 0.0:
            _values_any(w1, w2, inputs[t], h, scale, q, linear)
            if weights.shape[0] > 0:
                next_policy = _weighted_policy_probability(q, weights[t], a, temperature) >= p_threshold
            else:
                next_policy = _policy_probability(q, a, temperature) >= p_threshold
        else:
            next_policy = True
        if next_policy:
            _update_any(w1, w2, d1, d2, a, inputs[t], h, e, scale, lr, momentum, linear)
            used += 1
        if repair != 0:
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


def replay_oaon(net: OAON, lesson, params, repair: int = 0, weights=None, allowed=None, discounts=None) -> int:
    """Compiled incremental backward replay of one lesson into an OAON Q-function: the registered fast path
    of ``connrl.core.replay.replay_q`` (its arguments). ``repair`` 1/2 adds the lower/raise repairs of 5.4.3 after
    each experience."""
    n, a = len(lesson), net.n_nets
    d = np.full(n, float(params.gamma)) if discounts is None else np.ascontiguousarray(discounts, dtype=np.float64)
    w = np.zeros((0, a)) if weights is None else np.ascontiguousarray(weights, dtype=np.float64)
    m = np.zeros((0, a), dtype=np.bool_) if allowed is None else np.ascontiguousarray(allowed, dtype=np.bool_)
    return int(_replay_q_kernel(net.w1, net.w2, net.d1, net.d2, net._h, np.empty(a),
                                np.ascontiguousarray(lesson.inputs, dtype=np.float64),
                                np.ascontiguousarray(lesson.actions),
                                np.ascontiguousarray(lesson.rewards, dtype=np.float64), bool(lesson.terminated),
                                d, float(params.lam), float(params.temperature),
                                float(params.p_threshold), 0.0 if params.clip is None else float(params.clip),
                                params.clip is not None, net.scale, net.lr, net.config.momentum, int(repair),
                                net.config.linear_output, w, m))
