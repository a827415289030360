"""TD(lambda) returns as pure functions (Eq. 5.5, Fig. 5.1 step 4): no networks, no state."""

from __future__ import annotations

import numpy as np


def td_lambda_target(r: float, u_next: float, e_next: float, gamma: float, lam: float) -> float:
    """Eq. 5.5 / Fig. 5.1 step 4: ``e'_t = r_t + gamma [(1 - lam) u_{t+1} + lam e'_{t+1}]``."""
    return r + gamma * ((1.0 - lam) * u_next + lam * e_next)


def lambda_returns(rewards, next_values, gamma, lam, clip: float | None = None) -> np.ndarray:
    """TD(lambda) returns of a lesson computed backward (Eq. 5.5), for fixed predictions:
    ``e'_t = r_t + gamma_t [(1 - lam_t) u_{t+1} + lam_t e'_{t+1}]``.

    ``next_values[t]`` is ``u_{t+1}`` (0 after a terminal step). ``gamma`` is a scalar or a per-step array (n,),
    step t's discount ``gamma_t`` (rlax's ``discount_t``): gamma^k for a step that stands for k steps, as state
    grouping's ``connrl.core.grouping.group_lesson`` makes (6.6.4); a constant array equals the scalar. ``lam``
    is a scalar or a per-step array (use 0 where the following action was not a policy action); lambda is always 0
    at the last step. ``clip`` truncates targets from above (4.2.4: Q and V targets above 1 are set to 1).
    """
    rewards = np.asarray(rewards, dtype=np.float64)
    u = np.asarray(next_values, dtype=np.float64)
    gammas = _per_step_discounts(gamma, rewards.shape)
    lams = np.broadcast_to(np.asarray(lam, dtype=np.float64), rewards.shape)
    out = np.empty_like(rewards)
    e_next = 0.0
    for t in range(rewards.size - 1, -1, -1):
        lam_t = 0.0 if t == rewards.size - 1 else lams[t]
        e = td_lambda_target(rewards[t], u[t], e_next, gammas[t], lam_t)
        if clip is not None and e > clip:
            e = clip
        out[t] = e
        e_next = e
    return out


def _per_step_discounts(gamma, shape: tuple[int, ...]) -> np.ndarray:
    """A scalar gamma or an (n,) array as n per-step discounts; one clear ValueError for another shape."""
    arr = np.asarray(gamma, dtype=np.float64)
    if arr.ndim != 0 and arr.shape != shape:
        raise ValueError(f"gamma must be a number or one discount per step {shape}, got shape {arr.shape}")
    return np.broadcast_to(arr, shape)
