"""The nets' value scale for ``connrl.own.api``: the range +-value_range their outputs span, set from rewards seen.

A return is ``r_0 + g r_1 + ... + g^k r_k``. Rewards of steps that do not end the episode by termination can recur
every step, so they allow up to ``max |r_step| / (1 - g)``; a reward that terminates the episode comes once, at the
end. The return is then a weighted mean of the two bounds (weights ``1 - g^k`` and ``g^k``), so

    value_range = max(max |r_step| / (1 - g), max |r_end|)

bounds every return those rewards allow. Where every reward comes every step (CartPole, Acrobot, MountainCar) this
is the old rule ``max |r| / (1 - g)``; where the only reward ends the episode (a goal worth +1) it is that reward,
1, not 100: the Q-values fill the outputs' range and a temperature relative to the range sees their differences.

Until a non-zero reward is seen the range is provisional (``PROVISIONAL``): with every reward zero, every target is
zero and any scale describes the task equally well, so the first non-zero rewards set the range and the nets'
output scale is changed to it (``rescale``), which scales every Q-value by the same factor. Rewards seen later that
allow larger returns grow the range, keeping the Q-values learnt (``rescale(..., keep_q=True)``), unless the user
set the range.
"""

from __future__ import annotations

import dataclasses

import numpy as np

PROVISIONAL = 1.0  # the range before any non-zero reward is seen (any value would do: every target is 0)
MIN_ONE_MINUS_GAMMA = 1e-3  # gamma = 1: rewards that recur are taken to recur for at most ~1,000 steps


def reward_sizes(steps) -> tuple[float, float]:
    """``(max |r| of steps that did not terminate the episode, max |r| of steps that did)`` over ``steps``, pairs
    ``(reward, terminated)`` (0 where there are none)."""
    step_max = end_max = 0.0
    for r, terminated in steps:
        if terminated:
            end_max = max(end_max, abs(float(r)))
        else:
            step_max = max(step_max, abs(float(r)))
    return step_max, end_max


def range_for(step_max: float, end_max: float, gamma: float) -> float | None:
    """The largest |return| rewards of these sizes allow (module docstring); None while both are 0."""
    bound = max(step_max / max(1.0 - gamma, MIN_ONE_MINUS_GAMMA), end_max)
    return float(bound) if bound > 0 and np.isfinite(bound) else None


def rescale(nets, value_range: float, keep_q: bool = False) -> None:
    """Set the output scale of ``nets`` (OAON or recurrent nets, one or several) to +-``value_range``: every output
    is multiplied by ``value_range / old range``. With ``keep_q`` the output layer's weights (and their momentum) are
    multiplied by ``old range / value_range`` instead, which keeps every Q-value to first order in the output unit's
    net input (exactly at 0, closely in the sigmoid's linear part); outputs near the old range's edge, where targets
    beyond it were cut off, come out larger, towards those targets."""
    for net in nets:
        ratio = net.scale / (2.0 * float(value_range))
        net.scale = 2.0 * float(value_range)
        net.config = dataclasses.replace(net.config, value_range=float(value_range))
        if keep_q:
            net.w2 *= ratio
            net.d2 *= ratio
