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
def _update_any(w1, w2, d1, d2, a, x, h, target, scale, lr, momentum, linear):
    if w1.shape[1] > 0:
        _mlp_update(w1, w2, d1, d2, a, x, h, target, False, scale, lr, momentum)
    else:
        _perceptron_update(w2, d2, a, x, target, False, scale, lr, momentum, linear)


@numba.njit(cache=True, fastmath=True)
def _replay_q_kernel(w1, w2, d1, d2, h, q, inputs, actions, rewards, terminated, gamma, lam, temperature,
                     p_threshold, clip, has_clip, scale, lr, momentum, repair, linear):
    """Fig. 5.1(a) in incremental mode over a whole lesson; same arithmetic as ``replay_q_reference``.

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
            u = q.max()
        lam_t = lam if (t < n - 1 and next_policy) else 0.0
        e = rewards[t] + gamma * ((1.0 - lam_t) * u + lam_t * e_next)
        if has_clip and e > clip:
            e = clip
        a = actions[t]
        if p_threshold > 0.0:
            _values_any(w1, w2, inputs[t], h, scale, q, linear)
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
                best = -np.inf
                for i in range(q.shape[0]):
                    if i != a and q[i] > best:
                        best = q[i]
                if best > qa:
                    _update_any(w1, w2, d1, d2, a, inputs[t], h, best, scale, lr, momentum, linear)
        e_next = e
    return used


def replay_oaon(net: OAON, lesson, params, repair: int = 0) -> int:
    """Compiled incremental backward replay of one lesson into an OAON Q-function: the registered fast path
    of ``connrl.core.replay.replay_q``. ``repair`` 1/2 adds the lower/raise repairs of 5.4.3 after each
    experience."""
    return int(_replay_q_kernel(net.w1, net.w2, net.d1, net.d2, net._h, np.empty(net.n_nets),
                                np.ascontiguousarray(lesson.inputs, dtype=np.float64),
                                np.ascontiguousarray(lesson.actions),
                                np.ascontiguousarray(lesson.rewards, dtype=np.float64), bool(lesson.terminated),
                                float(params.gamma), float(params.lam), float(params.temperature),
                                float(params.p_threshold), 0.0 if params.clip is None else float(params.clip),
                                params.clip is not None, net.scale, net.lr, net.config.momentum, int(repair),
                                net.config.linear_output))
