"""TD(lambda) returns as pure functions (Eq. 5.5, Fig. 5.1 step 4): no networks, no state."""

from __future__ import annotations

import numpy as np


def td_lambda_target(r: float, u_next: float, e_next: float, gamma: float, lam: float) -> float:
    """Eq. 5.5 / Fig. 5.1 step 4: ``e'_t = r_t + gamma [(1 - lam) u_{t+1} + lam e'_{t+1}]``."""
    return r + gamma * ((1.0 - lam) * u_next + lam * e_next)


def lambda_returns(rewards, next_values, gamma: float, lam, clip: float | None = None) -> np.ndarray:
    """TD(lambda) returns of a lesson computed backward (Eq. 5.5), for fixed predictions.

    ``next_values[t]`` is ``u_{t+1}`` (0 after a terminal step). ``lam`` is a scalar or a per-step array
    (use 0 where the following action was not a policy action); lambda is always 0 at the last step.
    ``clip`` truncates targets from above (4.2.4: Q and V targets above 1 are set to 1).
    """
    rewards = np.asarray(rewards, dtype=np.float64)
    u = np.asarray(next_values, dtype=np.float64)
    lams = np.broadcast_to(np.asarray(lam, dtype=np.float64), rewards.shape)
    out = np.empty_like(rewards)
    e_next = 0.0
    for t in range(rewards.size - 1, -1, -1):
        lam_t = 0.0 if t == rewards.size - 1 else lams[t]
        e = td_lambda_target(rewards[t], u[t], e_next, gamma, lam_t)
        if clip is not None and e > clip:
            e = clip
        out[t] = e
        e_next = e
    return out
