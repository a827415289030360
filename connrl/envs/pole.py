"""Pole balancing exactly as the thesis's Appendix C (Barto, Sutton & Anderson 1983 dynamics with friction).

## Description
A pole hinged on a cart that moves along a 4.8 m track. The agent pushes the cart left or right with
10 N every 0.02 s and must keep the pole within 0.21 rad of upright and the cart within 2.4 m of the centre.

## Action Space
``Discrete(2)``: 0 pushes left (F = -10 N), 1 pushes right (F = +10 N).

## Observation Space
``observe="full"``: ``Box(4,)`` of (x, x_dot, theta, theta_dot); ``observe="x_theta"``: ``Box(2,)`` of
(x, theta) only (Task 4 of 7.5.4, a hidden-state task). With ``normalize=True`` (default) each quantity is
divided by a fixed scale (x: 2.4 m, x_dot: 2 m/s, theta: 0.21 rad, theta_dot: 2 rad/s) so that inputs are
of order 1, as a connectionist input layer wants; ``normalize=False`` gives SI units.

## Rewards
``r = -1`` on the step where ``|theta| > 0.21`` rad or ``|x| > 2.4`` m (App. C), else 0.

## Starting State
Training (default): x uniform in +-``start_x`` (1.2 m) and theta uniform in +-``start_theta`` (0.06 rad),
velocities 0 (7.5.4: "pole angles and cart positions were generated randomly"). A test start is given
with ``reset(options={"theta_deg": d})`` (x = 0, velocities 0); ``TEST_START_ANGLES_DEG`` lists the seven
starts of the thesis's test (0, +-1, +-2, +-3 degrees).

## Episode End
Terminated on failure (the step that gave r = -1). Truncated after ``max_steps`` (a time limit is not a
failure; learning bootstraps through it).

## Arguments
``observe`` ("full" | "x_theta"), ``normalize`` (bool), ``max_steps`` (int, default 10000),
``start_x``, ``start_theta`` (training start ranges).

## Differences from the thesis
Every reconstructed quantity, with the passage behind it: docs/RECONSTRUCTION.md, "Pole balancing".

- The ranges of the random training starts are not given (7.5.4); we use x in +-1.2 m and theta in
  +-0.06 rad (about +-3.4 degrees, just beyond the largest test start and the 3.3-degree limit).
- The input scaling is not given; see Observation Space.
- Gymnasium's CartPole-v1 differs: no friction, failure at 12 degrees = 0.2094 rad, reward +1 per step.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
from gymnasium import spaces

GRAVITY = 9.8  # m/s^2
CART_MASS = 1.0  # kg
POLE_MASS = 0.1  # kg
HALF_LENGTH = 0.5  # m
MU_CART = 0.0005  # friction of cart on track
MU_POLE = 0.000002  # friction of pole on cart
FORCE = 10.0  # N
TAU = 0.02  # s per step
THETA_LIMIT = 0.21  # rad
X_LIMIT = 2.4  # m
TEST_START_ANGLES_DEG = (0.0, 1.0, -1.0, 2.0, -2.0, 3.0, -3.0)
SCALES = np.array([2.4, 2.0, 0.21, 2.0])  # x, x_dot, theta, theta_dot (normalize=True)


def sgn(v: float) -> float:
    """App. C: +1 for v >= 0, -1 otherwise (note sgn(0) = +1)."""
    return 1.0 if v >= 0 else -1.0


def pole_step(state, force: float):
    """One Euler step of App. C's equations of motion; ``state`` = (x, x_dot, theta, theta_dot).

    The accelerations are evaluated at time t and then all four quantities advance by tau.
    """
    x, x_dot, theta, theta_dot = state
    sin_t, cos_t = math.sin(theta), math.cos(theta)
    total = CART_MASS + POLE_MASS
    fric_c = MU_CART * sgn(x_dot)
    theta_acc = (GRAVITY * sin_t + cos_t * ((-force - POLE_MASS * HALF_LENGTH * theta_dot ** 2 * sin_t + fric_c)
                                            / total) - MU_POLE * theta_dot / (POLE_MASS * HALF_LENGTH)) / (
        HALF_LENGTH * (4.0 / 3.0 - POLE_MASS * cos_t ** 2 / total))
    x_acc = (force + POLE_MASS * HALF_LENGTH * (theta_dot ** 2 * sin_t - theta_acc * cos_t) - fric_c) / total
    return (x + TAU * x_dot, x_dot + TAU * x_acc, theta + TAU * theta_dot, theta_dot + TAU * theta_acc)


def failed(state) -> bool:
    return abs(state[2]) > THETA_LIMIT or abs(state[0]) > X_LIMIT


class PoleBalancingEnv(gym.Env):
    metadata = {"render_modes": ["ansi"], "render_fps": 50}

    def __init__(self, observe: str = "full", normalize: bool = True, max_steps: int = 10_000,
                 start_x: float = 1.2, start_theta: float = 0.06, render_mode: str | None = None):
        if observe not in ("full", "x_theta"):
            raise ValueError(f"observe must be 'full' or 'x_theta', got {observe!r}")
        if max_steps < 1:
            raise ValueError(f"max_steps must be >= 1, got {max_steps}")
        if render_mode not in (None, "ansi"):
            raise ValueError(f"render_mode must be None or 'ansi', got {render_mode!r}")
        self.observe, self.normalize, self.max_steps = observe, normalize, max_steps
        self.start_x, self.start_theta = start_x, start_theta
        self.render_mode = render_mode
        self._idx = np.array([0, 1, 2, 3]) if observe == "full" else np.array([0, 2])
        self._scale = SCALES[self._idx] if normalize else np.ones(self._idx.size)
        self.action_space = spaces.Discrete(2)
        self.observation_space = spaces.Box(-np.inf, np.inf, (self._idx.size,), np.float64)
        self.state = (0.0, 0.0, 0.0, 0.0)
        self.steps = 0

    def _obs(self) -> np.ndarray:
        return np.asarray(self.state, dtype=np.float64)[self._idx] / self._scale

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        options = options or {}
        if "theta_deg" in options:
            self.state = (float(options.get("x", 0.0)), 0.0, math.radians(float(options["theta_deg"])), 0.0)
        else:
            x = self.np_random.uniform(-self.start_x, self.start_x)
            theta = self.np_random.uniform(-self.start_theta, self.start_theta)
            self.state = (float(x), 0.0, float(theta), 0.0)
        self.steps = 0
        return self._obs(), {"state": np.array(self.state)}

    def step(self, action):
        # a plain int in range needs no Gymnasium check (it costs more than the step itself)
        if not (action.__class__ is int and 0 <= action < 2) and not self.action_space.contains(action):
            raise ValueError(f"action must be 0 (left) or 1 (right), got {action!r}")
        self.state = pole_step(self.state, FORCE if int(action) == 1 else -FORCE)
        self.steps += 1
        terminated = failed(self.state)
        truncated = (not terminated) and self.steps >= self.max_steps
        return self._obs(), (-1.0 if terminated else 0.0), terminated, truncated, {"state": np.array(self.state)}

    def render(self):
        if self.render_mode != "ansi":
            return None
        x, _, theta, _ = self.state
        col = int(round((x + X_LIMIT) / (2 * X_LIMIT) * 48))
        track = ["-"] * 49
        track[min(max(col, 0), 48)] = "#"
        return "".join(track) + f"  x={x:+.3f} m  theta={math.degrees(theta):+.2f} deg  step {self.steps}"
