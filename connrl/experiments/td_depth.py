"""Fig. 5.2: the effective depth D of TD(lambda), measured from the code's own lambda-returns.

5.1.1 defines D as the temporal distance over which a TD(0) error's contribution to the learning of earlier
states decays to 1/e: ``1/e = lambda^D``, so ``D = -1/ln(lambda)``. Fig. 5.2 plots D against lambda ("D increases
gradually as lambda increases toward 0.9, and increases rapidly as lambda increases over 0.9").

Here D is not typed in: for each lambda, ``connrl.core.returns.lambda_returns`` (the function replay uses) computes
the returns of a long lesson whose only non-zero TD(0) error is a reward of 1 at its last step (all predictions 0,
gamma 1). The return k steps before it is then the weight ``w_k`` with which that error reaches a state k steps
back. D is where ``w_k`` crosses 1/e (log-linear between the two steps around it); the mean look-ahead
``sum k w_k / sum w_k`` is a second, looser sense of how far a lambda-return looks. Deterministic: one run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from connrl.core.returns import lambda_returns
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant, check_types, param

LAMS = (0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9,
        0.91, 0.92, 0.93, 0.94, 0.95, 0.96, 0.97, 0.98, 0.99)
MAX_LAMS = 1000  # lambda values measured in one run (Fig. 5.2's: 27), each a lesson of ``steps`` steps
MARKS = (0.7, 0.9, 0.99)  # D reported as quantities: the thesis's lambda for Ch. 5-6 (0.7), and both sides of 0.9


@dataclass(frozen=True)
class DepthParams:
    lams: tuple = param(LAMS, note="the lambda values measured (each in (0, 1))")
    steps: int = param(5000, ">=1", "lesson length: lambda^steps must be negligible for the largest lambda (0.99^5000 "
                       "~ 1e-22)")
    gamma: float = param(1.0, "0..1", "1: D is lambda's own depth, as 5.1.1 defines it (the code's weights are (gamma "
                         "lambda)^k)")

    def __post_init__(self):
        check_types(self)
        if len(self.lams) > MAX_LAMS:
            raise ValueError(f"parameter lams must have at most {MAX_LAMS} entries, got {len(self.lams)}")
        if not self.lams or not all(isinstance(x, float) and 0 < x < 1 for x in self.lams):
            raise ValueError(f"parameter lams must be numbers in (0, 1), got {self.lams!r}")

    def check_combination(self):
        if self.steps < 2 - 1.0 / math.log(max(self.lams)):  # the weight must fall to 1/e within the lesson
            raise ValueError(f"parameter steps must exceed D + 1 = {1 - 1.0 / math.log(max(self.lams)):.1f} for "
                             f"lambda = {max(self.lams):g}, got {self.steps}")


def return_weights(lam: float, steps: int, gamma: float = 1.0) -> np.ndarray:
    """``w[k]``: the lambda-return of the state k steps before a lone TD(0) error of 1 (the lesson's last reward)."""
    rewards = np.zeros(steps)
    rewards[-1] = 1.0
    return lambda_returns(rewards, np.zeros(steps), gamma, lam)[::-1]


def decay_depth(w: np.ndarray) -> float | None:
    """Where the weights first fall to 1/e of ``w[0]``, log-linear between the steps around it (None: not within
    the lesson)."""
    below = np.flatnonzero(w <= w[0] / math.e)
    if below.size == 0 or below[0] == 0:
        return None
    k = int(below[0])
    hi, lo = math.log(w[k - 1] / w[0]), math.log(w[k] / w[0]) if w[k] > 0 else -math.inf
    return (k - 1) + (hi + 1.0) / (hi - lo)


def mean_lookahead(w: np.ndarray) -> float:
    """The weights' mean distance ``sum k w_k / sum w_k`` (``lambda / (1 - lambda)`` for geometric weights)."""
    return float(np.arange(w.size) @ w / w.sum())


def run_depth(p: DepthParams, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    rows = []
    for i, lam in enumerate(p.lams):
        w = return_weights(lam, p.steps, p.gamma)
        rows.append({"lam": lam, "depth": decay_depth(w), "formula": -1.0 / math.log(lam),
                     "mean_lookahead": mean_lookahead(w)})
        progress(i + 1, len(p.lams))
    metrics: dict[str, float | None] = {
        "max_rel_deviation": max(abs(r["depth"] - r["formula"]) / r["formula"] for r in rows)}
    for lam in MARKS:
        metrics[f"depth_{lam:g}"] = next((r["depth"] for r in rows if r["lam"] == lam), None)
    return RunResult([r["lam"] for r in rows], [r["depth"] for r in rows], metrics, rows)


QUANTITIES = (Quantity("max_rel_deviation", "largest |D - (-1/ln lambda)| / (-1/ln lambda) over the lambdas measured",
                       "lower", "5.1.1"),
              *(Quantity(f"depth_{lam:g}", f"D at lambda = {lam:g}: steps back to a weight of 1/e", "lower",
                         "5.1.1, Fig. 5.2") for lam in MARKS))

# the thesis's D is its formula (the results page sets it beside each D); a deviation under 1e-6 of it (float
# rounding over thousands of steps) is a match
THESIS = {"max_rel_deviation": 1e-6}

CHAPTER = 5  # the thesis chapter of these experiments (`connrl reproduce --chapters`)
EXPERIMENTS = [
    ExperimentSpec(
        name="td-depth", title="The effective depth D of TD(lambda) against lambda, from the code's lambda-returns",
        section="5.1.1, Fig. 5.2", run="connrl.experiments.td_depth:run_depth", params=DepthParams(),
        profiles={"tiny": {"runs": 1, "lams": (0.5, 0.7, 0.9, 0.99), "steps": 2000}, "quick": {"runs": 1},
                  "full": {"runs": 1}},
        variants=(Variant("lambda-returns (gamma = 1)", thesis=THESIS),), quantities=QUANTITIES,
        x_label="lambda", y_label="D (steps to a weight of 1/e)",
        description="deterministic: the weight with which one TD(0) error reaches earlier states, from "
                    "connrl.core.returns.lambda_returns; the thesis's D = -1/ln(lambda)"),
]
