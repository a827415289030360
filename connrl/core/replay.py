"""Backward TD(lambda) replay of a lesson (Fig. 5.1), with the repairs of 5.4.3.

The loops apply the pure returns of ``connrl.core.returns`` to networks in the order of Fig. 5.1: backward
from t = n-1, with lambda set to 0 at the last step and after a non-policy action, and non-policy
experiences not replayed (3.5.1). Incremental mode updates after each experience (the default, 5.1.2);
batch mode computes every target from the networks as they were before the lesson, then updates (7.5).

``replay_q_reference`` is the readable loop of Fig. 5.1(a); ``replay_q`` runs the same loop through a
registered compiled fast path when there is one for the Q-function's type (``FAST_PATHS``: an OAON's
whole lesson in one Numba kernel, ``connrl.core.replay_kernel``), and the reference loop otherwise.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numba
import numpy as np

from connrl.core.exploration import boltzmann_probabilities, weighted_boltzmann_probabilities
from connrl.core.lessons import Lesson, pack_lessons
from connrl.core.replay_kernel import replay_ahc_rotated, replay_oaon, replay_oaon_lessons, replay_rotated
from connrl.core.returns import lambda_returns, td_lambda_target
from connrl.nets.kernels import replay_settings
from connrl.nets.mlp import OAON
from connrl.nets.rotated import RotatedNet

REPAIRS = ("none", "lower", "raise")  # 5.4.3; "none" = plain replay


class QFunction(Protocol):
    """What replay needs of a Q-function: all action values, and a step toward a target for one action."""

    n_actions: int

    def values(self, x: np.ndarray) -> np.ndarray: ...

    def update(self, x: np.ndarray, a: int, target: float) -> float: ...


@dataclass(frozen=True)
class ReplayParams:
    """How one lesson is replayed (Fig. 5.1, 3.5.1, 5.1.2)."""

    gamma: float  # discount factor (3.2)
    lam: float = 0.0  # recency factor lambda of TD(lambda) (5.1); Ch. 3-4 use 0
    temperature: float = 0.0  # T of the current policy, for the non-policy test (3.5.1)
    p_threshold: float = 0.0  # P_t: actions with P(a|x) below it are non-policy, not replayed (3.5.1)
    batch: bool = False  # batch mode: targets from the nets as before the lesson (5.1.2, 7.5)
    clip: float | None = None  # truncate targets above this value (4.2.4)

    @functools.cached_property
    def kernel_settings(self) -> tuple:
        """``(lam, temperature, p_threshold, clip, has_clip)``: the replay as a compiled kernel takes it
        (``connrl.nets.kernels.replay_settings``)."""
        return replay_settings(self.lam, self.temperature, self.p_threshold, self.clip)


def is_policy_action(merits: np.ndarray, a: int, params: ReplayParams, weights: np.ndarray | None = None) -> bool:
    """3.5.1: an action is a policy action when its Boltzmann probability is at least P_t; with ``weights`` the
    probability is Eq. 6.6's, W(b) as it was when the step was taken (6.6: bad behaviour choices not replayed)."""
    if params.p_threshold <= 0:
        return True
    p = (boltzmann_probabilities(merits, params.temperature) if weights is None
         else weighted_boltzmann_probabilities(merits, weights, params.temperature))
    return bool(p[a] >= params.p_threshold)


def policy_mask(values: np.ndarray, actions: np.ndarray, params: ReplayParams,
                weights: np.ndarray | None = None) -> np.ndarray:
    """``is_policy_action`` at every step of a lesson at once: values (n, A) before each action, weights (n, A) or
    None; (n,) bool. Vectorised for batch replay's long lessons (Ch. 8); the same arithmetic as the per-step test."""
    n = len(actions)
    if params.temperature < 0:
        raise ValueError(f"temperature must be >= 0, got {params.temperature}")
    if params.p_threshold <= 0:
        return np.ones(n, dtype=bool)
    if params.temperature == 0:  # greedy: ties share the mass; the per-step rule handles it
        return np.array([is_policy_action(values[t], int(actions[t]), params, None if weights is None else weights[t])
                         for t in range(n)], dtype=bool)
    m = np.asarray(values, dtype=np.float64)
    w = np.ones_like(m) if weights is None else np.asarray(weights, dtype=np.float64)
    if w.shape != m.shape or np.any(w < 0) or not np.all((w > 0).any(axis=1)):
        raise ValueError(f"weights must be (n, actions) = {m.shape}, >= 0, not all 0 in a row")
    top = np.where(w > 0, m, -np.inf).max(axis=1, keepdims=True)
    e = np.where(w > 0, w * np.exp((m - top) / params.temperature), 0.0)
    p = e[np.arange(n), np.asarray(actions, dtype=int)] / e.sum(axis=1)
    return p >= params.p_threshold


def repair_step(q: QFunction, x: np.ndarray, a: int, mode: str) -> int:
    """One 5.4.3 repair of the taught action ``a`` at input ``x`` (Eq. 5.6); returns the nets changed.

    ``lower``: every other action valued above ``a`` is moved toward ``Q(x, a)``.
    ``raise``: ``a`` is moved toward the largest other value when that exceeds ``Q(x, a)``.
    """
    if mode not in REPAIRS:
        raise ValueError(f"repair must be one of {REPAIRS}, got {mode!r}")
    if mode == "none":
        return 0
    v = np.asarray(q.values(x), dtype=np.float64)
    others = np.delete(np.arange(v.size), a)
    if mode == "lower":
        changed = 0
        for i in others:
            if v[i] > v[a]:
                q.update(x, int(i), float(v[a]))
                changed += 1
        return changed
    best = int(others[np.argmax(v[others])])
    if v[best] > v[a]:
        q.update(x, a, float(v[best]))
        return 1
    return 0


def batch_targets(values: np.ndarray, actions: np.ndarray, rewards: np.ndarray, terminated: bool,
                  params: ReplayParams, weights: np.ndarray | None = None,
                  allowed: np.ndarray | None = None,
                  discounts: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Fig. 5.1(a) in batch mode: every target of a lesson from fixed predictions (5.1.2, 7.5).

    ``values`` (n+1, A) are the Q-values along the lesson before any update. Returns ``(targets (n,),
    policy (n,) bool)``: a non-policy action is not replayed and cuts lambda for the step before it
    (lambda is also 0 at the last step). ``weights``, ``allowed`` and ``discounts`` as ``replay_q_reference``'s (Ch.
    6's W of Eq. 6.6 in the non-policy test; the actions each state's max ranges over; state grouping's per-step
    discounts, 6.6.4). Pure.
    """
    values = np.asarray(values, dtype=np.float64)
    n = len(actions)
    if values.shape[0] != n + 1:
        raise ValueError(f"values must have n+1={n + 1} rows for a lesson of {n} steps, got {values.shape}")
    if allowed is not None and np.shape(allowed) != values.shape:
        raise ValueError(f"allowed must be (n+1, actions) = {values.shape}, got {np.shape(allowed)}")
    policy = policy_mask(values[:n], actions, params, weights)
    nxt = values[1:]
    if allowed is not None:
        ok = np.asarray(allowed, dtype=bool)[1:]
        nxt = np.where(ok | ~ok.any(axis=1, keepdims=True), nxt, -np.inf)  # all actions where none is allowed
    u = nxt.max(axis=1)
    if terminated:
        u[-1] = 0.0
    lams = np.where(np.append(policy[1:], False), params.lam, 0.0)
    gamma = params.gamma if discounts is None else discounts
    return lambda_returns(rewards, u, gamma, lams, params.clip), policy


def replay_q_reference(q: QFunction, lesson: Lesson, params: ReplayParams, repair: str = "none",
                       weights: np.ndarray | None = None, allowed: np.ndarray | None = None,
                       discounts: np.ndarray | None = None) -> int:
    """Fig. 5.1(a), the plain loop: replay a lesson backward into a Q-function; returns the experiences used.

    With ``repair`` (taught lessons, 5.4.3) the repair check follows the TD update of each experience, with
    the net as it is then (the thesis does not say when within the replay). Ch. 6's options: ``weights`` (n,
    actions), each step's W of Eq. 6.6 for the non-policy test; ``allowed`` (n+1, actions, bool), the actions the
    target's max ranges over in each state (all where none is allowed); ``discounts`` (n,), each step's discount in
    place of gamma (gamma^k for a step that stands for k, as ``group_lesson`` makes, 6.6.4).
    """
    x, acts, rews = lesson.inputs, lesson.actions, lesson.rewards
    n = len(lesson)
    _check_step_arrays(lesson, weights, allowed, discounts)
    if params.batch:
        if repair != "none":
            raise ValueError("the 5.4.3 repairs are defined for incremental replay only")
        targets, policy = batch_targets(np.array([q.values(x[t]) for t in range(n + 1)]), acts, rews,
                                        lesson.terminated, params, weights, allowed, discounts)
        for t in range(n - 1, -1, -1):
            if policy[t]:
                q.update(x[t], int(acts[t]), targets[t])
        return int(policy.sum())
    used = 0
    e_next, next_policy = 0.0, False
    for t in range(n - 1, -1, -1):
        u = 0.0
        if not (t == n - 1 and lesson.terminated):
            v = np.asarray(q.values(x[t + 1]), dtype=np.float64)
            ok = None if allowed is None else np.asarray(allowed[t + 1], dtype=bool)
            u = float(v[ok].max()) if ok is not None and ok.any() else float(v.max())
        lam_t = params.lam if (t < n - 1 and next_policy) else 0.0
        gamma = params.gamma if discounts is None else float(discounts[t])
        e = td_lambda_target(rews[t], u, e_next, gamma, lam_t)
        if params.clip is not None and e > params.clip:
            e = params.clip
        a = int(acts[t])
        next_policy = is_policy_action(q.values(x[t]), a, params, None if weights is None else weights[t])
        if next_policy:
            q.update(x[t], a, e)
            used += 1
        if repair != "none":
            repair_step(q, x[t], a, repair)
        e_next = e
    return used


def _check_step_arrays(lesson: Lesson, weights, allowed, discounts) -> None:
    if weights is None and allowed is None and discounts is None:
        return
    n = len(lesson)
    for name, arr, rows in (("weights", weights, n), ("allowed", allowed, n + 1), ("discounts", discounts, n)):
        if arr is not None and len(arr) != rows:
            raise ValueError(f"{name} must have {rows} rows for a lesson of {n} steps, got {len(arr)}")


# type of Q-function -> compiled whole-lesson replay ``fn(q, lesson, params, repair_index, weights, allowed,
# discounts) -> used`` (None: not compiled for these options, the reference loop replays)
FAST_PATHS: dict[type, Callable[..., int]] = {}
# (type of V-net, type of policy net) -> compiled whole-lesson Fig. 5.1(b) ``fn(v_net, policy_net, lesson, params)``
AHC_FAST_PATHS: dict[tuple[type, type], Callable[..., int]] = {}


def register_fast_path(q_type: type, fn: Callable[..., int]) -> None:
    """Declare a compiled replay for ``q_type`` that must equal ``replay_q_reference`` (incremental mode)."""
    FAST_PATHS[q_type] = fn


def replay_q(q: QFunction, lesson: Lesson, params: ReplayParams, repair: str = "none", fast: bool = True,
             weights: np.ndarray | None = None, allowed: np.ndarray | None = None,
             discounts: np.ndarray | None = None) -> int:
    """Fig. 5.1(a): the registered fast path for ``type(q)`` in incremental mode, else the reference loop (the
    per-step options as ``replay_q_reference``'s)."""
    fn = FAST_PATHS.get(type(q)) if fast and not params.batch else None
    if fn is None:
        return replay_q_reference(q, lesson, params, repair, weights, allowed, discounts)
    if repair not in REPAIRS:
        raise ValueError(f"repair must be one of {REPAIRS}, got {repair!r}")
    _check_step_arrays(lesson, weights, allowed, discounts)
    check_lesson_fits(lesson, q.n_actions, q.config.n_inputs)
    used = fn(q, lesson, params, REPAIRS.index(repair), weights, allowed, discounts)
    return replay_q_reference(q, lesson, params, repair, weights, allowed, discounts) if used is None else used


def replay_q_lessons(q, lessons: list[Lesson], thresholds: list[float], params: ReplayParams, options) -> int:
    """``replay_q`` on each of ``lessons`` in turn (the same lesson may come again): lesson k at P_t
    ``thresholds[k]`` and with ``options(lesson)`` = its (weights, allowed), no repairs, incremental mode. An OAON
    replays them all in one compiled call (issue 45: up to a thousand a trial in Ch. 8), each distinct lesson
    checked once; any other Q-function one by one."""
    if type(q) is not OAON or params.batch or FAST_PATHS.get(OAON) is not replay_oaon:
        return sum(replay_q(q, lesson, dataclasses.replace(params, p_threshold=p), "none", True, *options(lesson))
                   for lesson, p in zip(lessons, thresholds, strict=True))
    if len(lessons) != len(thresholds):
        raise ValueError(f"{len(lessons)} lessons and {len(thresholds)} thresholds")
    if not lessons:
        return 0

    def check(lesson, weights, allowed):
        _check_step_arrays(lesson, weights, allowed, None)
        check_lesson_fits(lesson, q.n_actions, q.config.n_inputs)
        for name, arr in (("weights", weights), ("allowed", allowed)):  # the kernel indexes their rows unchecked
            if arr is not None and np.shape(arr)[1:] != (q.n_actions,):
                raise ValueError(f"{name} must have one column per action ({q.n_actions}), got shape {np.shape(arr)}")

    return replay_oaon_lessons(q, pack_lessons(lessons, options, q.n_actions, check), thresholds, params)


@numba.njit(cache=True)
def _actions_fit(actions, n_actions):
    """Every action in 0..n_actions - 1: one compiled pass (issue 45: a tenth of the two reductions it replaces,
    on every one of up to 150,000 lessons a run)."""
    for a in actions:
        if a < 0 or a >= n_actions:
            return False
    return True


def check_lesson_fits(lesson: Lesson, n_actions: int, n_inputs: int) -> None:
    """Refuse a lesson whose actions or input width do not fit the nets: the compiled kernels index without bounds
    (a loaded file is checked before it gets here; this keeps a lesson built by hand from corrupting memory)."""
    a = lesson.actions
    fits = _actions_fit(a, n_actions) if a.dtype == np.int64 else not len(a) or (a.min() >= 0 and a.max() < n_actions)
    if not fits or lesson.inputs.shape[1] != n_inputs:
        raise ValueError(f"a lesson with actions in [{a.min()}, {a.max()}] and {lesson.inputs.shape[1]} inputs does "
                         f"not fit nets of actions 0..{n_actions - 1} on {n_inputs} inputs")


def ahc_batch_targets(v_values: np.ndarray, merits: np.ndarray, actions: np.ndarray, rewards: np.ndarray,
                      terminated: bool, params: ReplayParams) -> tuple[np.ndarray, np.ndarray]:
    """Fig. 5.1(b) in batch mode: every V target of a lesson from fixed predictions (5.1.2), as ``batch_targets``.

    ``v_values`` (n+1,) are V(x_0..x_n) and ``merits`` (n, A) the policy net's merits before any update. Returns
    ``(targets (n,), policy (n,) bool)``: the non-policy test is on the merits (3.5.1); a non-policy action is not
    replayed and cuts lambda for the step before it (lambda is also 0 at the last step). Pure.
    """
    n = len(actions)
    u = np.array(v_values, dtype=np.float64)[1:]
    if u.shape != (n,):
        raise ValueError(f"v_values must have n+1={n + 1} entries for a lesson of {n} steps, got {len(u) + 1}")
    if terminated:
        u[-1] = 0.0
    policy = policy_mask(merits, actions, params)
    lams = np.where(np.append(policy[1:], False), params.lam, 0.0)
    return lambda_returns(rewards, u, params.gamma, lams, params.clip), policy


def replay_ahc(v_net, policy_net, lesson: Lesson, params: ReplayParams, fast: bool = True) -> int:
    """Fig. 5.1(b): the registered compiled path for the nets' types in incremental mode
    (``AHC_FAST_PATHS``), else the reference loop ``replay_ahc_reference``."""
    fn = AHC_FAST_PATHS.get((type(v_net), type(policy_net))) if fast and not params.batch else None
    if fn is None:
        return replay_ahc_reference(v_net, policy_net, lesson, params)
    check_lesson_fits(lesson, policy_net.n_actions, policy_net.config.n_inputs)
    used = fn(v_net, policy_net, lesson, params)
    return replay_ahc_reference(v_net, policy_net, lesson, params) if used is None else used


def replay_ahc_reference(v_net, policy_net, lesson: Lesson, params: ReplayParams) -> int:
    """Fig. 5.1(b), the plain loop: replay a lesson backward into a V-net (one output) and a policy net (one per
    action).

    Non-policy actions are judged by the Boltzmann probabilities of the policy net's merits (3.5.1). Each replayed
    experience moves V(x_t) toward its target e_t and the taken action's merit by the same error, e_t - V(x_t) with
    V as it is just before that step (Fig. 3.2 steps 5-6). In batch mode (5.1.2) the targets and the non-policy test
    come from the nets as they were before the lesson (``ahc_batch_targets``), as ``replay_q_reference``'s do.
    """
    x, acts, rews = lesson.inputs, lesson.actions, lesson.rewards
    n = len(lesson)
    if params.batch and n > 0:
        targets, policy = ahc_batch_targets(np.array([v_net.value(x[t], 0) for t in range(n + 1)]),
                                            np.array([policy_net.values(x[t]) for t in range(n)]).reshape(n, -1),
                                            acts, rews, lesson.terminated, params)
        for t in range(n - 1, -1, -1):
            if policy[t]:
                v_before = v_net.update(x[t], 0, targets[t])
                policy_net.update_error(x[t], int(acts[t]), targets[t] - v_before)
        return int(policy.sum())
    used = 0
    e_next, next_policy = 0.0, False
    for t in range(n - 1, -1, -1):
        u = 0.0 if (t == n - 1 and lesson.terminated) else float(v_net.value(x[t + 1], 0))
        lam_t = params.lam if (t < n - 1 and next_policy) else 0.0
        e = td_lambda_target(rews[t], u, e_next, params.gamma, lam_t)
        if params.clip is not None and e > params.clip:
            e = params.clip
        a = int(acts[t])
        next_policy = is_policy_action(policy_net.values(x[t]), a, params)
        if next_policy:
            v_before = v_net.update(x[t], 0, e)
            policy_net.update_error(x[t], a, e - v_before)
            used += 1
        e_next = e
    return used


register_fast_path(OAON, replay_oaon)
register_fast_path(RotatedNet, replay_rotated)
AHC_FAST_PATHS[(OAON, RotatedNet)] = replay_ahc_rotated
