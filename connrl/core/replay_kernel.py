"""The compiled fast path of Fig. 5.1(a): a whole lesson replayed into an OAON by one Numba kernel.

Per-sample replay of tiny nets is dominated by interpreter overhead, so the incremental backward loop of
``connrl.core.replay.replay_q_reference`` is compiled over the OAON's stacked weight arrays (see
benchmarks/bench_core.py). ``tests/core/test_replay.py`` checks it against the plain loop. The kernel itself,
``_replay_q_kernel``, lives in ``connrl.nets.kernels`` beside the net kernels it inlines, so that Numba's cache (keyed
on one source file) can never hold a replay compiled against older net arithmetic (issue 25).
"""

from __future__ import annotations

import numpy as np

from connrl.core.lessons import LessonPack
from connrl.nets.kernels import (
    _replay_ahc_rotated_kernel,
    _replay_q_kernel,
    _replay_q_lessons,
    _replay_rotated_kernel,
)
from connrl.nets.mlp import OAON
from connrl.nets.rotated import RotatedNet


def _lesson_arrays(lesson) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A lesson's inputs, actions and rewards as the kernels take them (contiguous float64 / int64 / float64)."""
    return (np.ascontiguousarray(lesson.inputs, dtype=np.float64), np.ascontiguousarray(lesson.actions, dtype=np.int64),
            np.ascontiguousarray(lesson.rewards, dtype=np.float64))


# Arrays the kernels only read, made once (issue 45: a run replays up to 150,000 lessons): gamma per step, and the
# empty (0, A) arrays that mean "no per-step weights / allowed choices". Never written: they are shared.
_GAMMAS: dict[float, np.ndarray] = {}
_NONE: dict[tuple, np.ndarray] = {}


def _gammas(n: int, gamma: float) -> np.ndarray:
    """``np.full(n, gamma)``: a view of a kept array (writable, so the kernels' signature is the one they were
    compiled and cached for; they never write it)."""
    d = _GAMMAS.get(gamma)
    if d is None or d.size < n:
        d = _GAMMAS[gamma] = np.full(max(n, 256, 0 if d is None else 2 * d.size), gamma)
    return d[:n]


def _none(a: int, dtype) -> np.ndarray:
    """``np.zeros((0, a), dtype)``, kept."""
    z = _NONE.get((a, dtype))
    if z is None:
        z = _NONE[(a, dtype)] = np.zeros((0, a), dtype=dtype)
    return z


def replay_oaon(net: OAON, lesson, params, repair: int = 0, weights=None, allowed=None, discounts=None) -> int:
    """Compiled incremental backward replay of one lesson into an OAON Q-function: the registered fast path
    of ``connrl.core.replay.replay_q`` (its arguments). ``repair`` 1/2 adds the lower/raise repairs of 5.4.3 after
    each experience."""
    n, a = len(lesson), net.n_nets
    d = _gammas(n, float(params.gamma)) if discounts is None else np.ascontiguousarray(discounts, dtype=np.float64)
    w = _none(a, np.float64) if weights is None else np.ascontiguousarray(weights, dtype=np.float64)
    m = _none(a, np.bool_) if allowed is None else np.ascontiguousarray(allowed, dtype=np.bool_)
    return int(_replay_q_kernel(net.kernel_arrays, net.kernel_settings, np.empty(a), *_lesson_arrays(lesson),
                                bool(lesson.terminated), d, params.kernel_settings, int(repair), w, m))


def replay_oaon_lessons(net: OAON, pack: LessonPack, thresholds: np.ndarray, params) -> int:
    """Compiled ``replay_oaon`` on ``pack.order``'s lessons in turn, the k-th at P_t ``thresholds[k]``, in one call:
    the fast path of ``connrl.core.replay.replay_q_lessons`` (its checks made)."""
    return int(_replay_q_lessons(net.kernel_arrays, net.kernel_settings, np.empty(net.n_nets), pack.inputs,
                                 pack.actions, pack.rewards, pack.terminated,
                                 _gammas(int(pack.step_start[-1]), float(params.gamma)), pack.in_start,
                                 pack.step_start, pack.order, np.asarray(thresholds, dtype=np.float64),
                                 params.kernel_settings, pack.weights, pack.allowed))


def replay_rotated(net: RotatedNet, lesson, params, repair: int = 0, weights=None, allowed=None,
                   discounts=None) -> int | None:
    """Compiled incremental backward replay of one lesson into a rotated net (4.2.4): the registered fast path of
    ``connrl.core.replay.replay_q`` for Ch. 4's nets, bit for bit the reference loop's
    (tests/core/test_replay_compiled.py). The 5.4.3 repairs and Ch. 6's per-step weights and allowed choices, which
    Ch. 4 does not use, are not compiled: None sends them to the reference loop."""
    if repair or weights is not None or allowed is not None:
        return None
    n, o = len(lesson), net.net
    d = _gammas(n, float(params.gamma)) if discounts is None else np.ascontiguousarray(discounts, dtype=np.float64)
    return int(_replay_rotated_kernel(o.kernel_arrays, (o.scale, o.lr, net.config.momentum), net._xr,
                                      np.empty(net.n_actions), net.perms, *_lesson_arrays(lesson),
                                      bool(lesson.terminated), d, params.kernel_settings))


def replay_ahc_rotated(v_net: OAON, policy: RotatedNet, lesson, params) -> int | None:
    """Compiled incremental Fig. 5.1(b) into Ch. 4's AHCON nets (a V-net with a hidden layer, a rotated policy net):
    the registered fast path of ``connrl.core.replay.replay_ahc``, bit for bit the reference loop's."""
    if v_net.config.n_hidden == 0 or v_net.n_nets != 1:
        return None  # a perceptron V-net is not compiled: the reference loop
    p = policy.net
    return int(_replay_ahc_rotated_kernel(
        v_net.kernel_arrays, (v_net.scale, v_net.lr, v_net.config.momentum), p.kernel_arrays,
        (p.scale, p.lr, policy.config.momentum), policy._xr, np.empty(policy.n_actions), policy.perms,
        *_lesson_arrays(lesson), bool(lesson.terminated), float(params.gamma), params.kernel_settings))
