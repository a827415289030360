"""Observations into the nets' input code, and the random-policy warm-up that sets it (connrl.own.api's docstring,
"Inputs")."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from connrl.own.spaces import affine_scales, flat_scales, flatten


class InputScaler:
    """Observations into the nets' input code (module docstring): ``encode(obs) -> float64 vector``."""

    def __init__(self, kind: str, n: int, offset: np.ndarray | None = None, scale: np.ndarray | None = None,
                 space=None):
        self.kind, self.n, self.space = kind, int(n), space  # "flat" (composite spaces) flattens obs by the space
        self.offset = np.zeros(self.n) if offset is None else np.asarray(offset, float)
        self.scale = np.ones(self.n) if scale is None else np.asarray(scale, float)

    @classmethod
    def fit(cls, space, samples: np.ndarray, by: str = "bounds") -> InputScaler:
        """Scales for ``space`` from a random policy's observations ``samples``; ``by``: how bounded Box units are
        scaled, by their bounds or by the samples' spread (``connrl.own.spaces.affine_scales``)."""
        if isinstance(space, spaces.Discrete):
            return cls("onehot", space.n, offset=np.full(space.n, float(space.start)))
        if isinstance(space, spaces.Box):
            offset, scale = affine_scales(space.low, space.high, samples, by)
            return cls("affine", offset.size, offset, scale)
        offset, scale = flat_scales(space, samples, by)  # Dict, Tuple, MultiDiscrete, MultiBinary (connrl.own.spaces)
        return cls("flat", offset.size, offset, scale, space)

    @property
    def n_inputs(self) -> int:
        return self.n

    def encode(self, obs) -> np.ndarray:
        if self.kind == "onehot":
            out = np.full(self.n, -0.5)
            out[int(obs) - int(self.offset[0])] = 0.5  # the offset holds the space's start
            return out
        x = flatten(self.space, obs) if self.kind == "flat" else np.asarray(obs, float).ravel()
        return (x - self.offset) / self.scale

    def encode_row(self, row) -> np.ndarray:
        """A lesson file's input row (``observation_row``: a composite observation already flattened) encoded."""
        if self.kind == "onehot":  # a Discrete observation's row holds the one number
            return self.encode(np.asarray(row).ravel()[0])
        return (np.asarray(row, float) - self.offset) / self.scale if self.kind == "flat" else self.encode(row)

    def to_json(self) -> dict:
        return {"kind": self.kind, "n": self.n, "offset": self.offset.tolist(), "scale": self.scale.tolist()}

    @classmethod
    def from_json(cls, d: dict, space=None) -> InputScaler:
        return cls(d["kind"], d["n"], d["offset"], d["scale"], space)


class ScaledEnv(gym.ObservationWrapper):
    """The env as the learner sees it: observations encoded, its trial's steps counted, reward sizes watched."""

    def __init__(self, env, scaler: InputScaler):
        super().__init__(env)
        self.scaler = scaler
        self.observation_space = spaces.Box(-np.inf, np.inf, (scaler.n_inputs,), np.float64)
        self.steps = 0  # of the current trial: what a trial cut by Ctrl-C took
        self.sizes = (0.0, 0.0)  # connrl.own.value_scale.reward_sizes of the rewards it has passed on
        self.on_sizes = None  # called with the new sizes when they grow

    def observation(self, observation):
        return self.scaler.encode(observation)

    def reset(self, **kwargs):
        self.steps = 0
        return super().reset(**kwargs)

    def step(self, action):
        obs, r, terminated, truncated, info = super().step(action)
        self.steps += 1
        i = int(bool(terminated))
        if abs(float(r)) > self.sizes[i]:
            self.sizes = (abs(float(r)), self.sizes[1]) if i == 0 else (self.sizes[0], abs(float(r)))
            if self.on_sizes is not None:
                self.on_sizes(self.sizes)
        return obs, r, terminated, truncated, info


def warmup(env, steps: int, rng: np.random.Generator) -> tuple[list, list, list]:
    """Observations, every step's (reward, terminated) and the episodes (observations, actions, rewards, terminated)
    of ``steps`` random-policy steps (at least one observation)."""
    obs, _ = env.reset(seed=int(rng.integers(2**31)))
    seen, rewards, episodes, ep = [obs], [], [], ([obs], [], [])
    for _ in range(steps):
        a = int(rng.integers(env.action_space.n))
        obs, r, terminated, truncated, _ = env.step(a)
        seen.append(obs)
        ep[0].append(obs)
        ep[1].append(a)
        ep[2].append(float(r))
        rewards.append((float(r), bool(terminated)))
        if terminated or truncated:
            episodes.append((*ep, bool(terminated)))
            obs, _ = env.reset(seed=int(rng.integers(2**31)))
            seen.append(obs)
            ep = ([obs], [], [])
    return seen, rewards, episodes  # raw: a Dict observation is no array
