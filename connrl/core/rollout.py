"""One trial of the agent protocol in any Gymnasium environment: the thesis's training trial or test trial.

Training (``learning=True``): stochastic actions, the agent observes each step (on-line learning, Figs. 3.2
and 3.4) and replays after the trial (3.5). Test (``learning=False``): the greedy policy (T = 0), nothing
learned. ``terminated`` and ``truncated`` stay distinct: a timeout is not a failure.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import gymnasium as gym


@dataclass
class TrialStats:
    steps: int
    total_reward: float
    terminated: bool
    truncated: bool
    info: dict = field(default_factory=dict)


def run_trial(env, agent, *, trial: int, learning: bool, seed: int | None = None, options: dict | None = None,
              max_steps: int | None = None, on_step=None) -> TrialStats:
    """Play one trial. With ``learning`` the agent observes each step and replays after the trial;
    without it the agent acts greedily (T = 0) and nothing is learned (the thesis's test phase).
    ``max_steps`` cuts the trial there: a timeout (truncated), which a learning agent observes as one, so replay
    bootstraps through it; ``on_step(info)`` sees every step.
    """
    obs, info = env.reset(seed=seed, options=options)
    agent.begin_trial(obs, info, trial=trial, learning=learning)
    steps, total = 0, 0.0
    terminated = truncated = False
    while True:
        a = agent.act(obs, info, greedy=not learning)
        obs, r, terminated, truncated, info = env.step(a)
        steps += 1
        total += float(r)
        if max_steps is not None and steps >= max_steps and not terminated:
            truncated = True
        if learning:
            agent.observe(a, r, obs, terminated, truncated, info)
        if on_step is not None:
            on_step(info)
        if terminated or truncated:
            break
    agent.end_trial()
    if learning:
        agent.learn()
    return TrialStats(steps, total, bool(terminated), bool(truncated), info)


MAX_EPISODE_STEPS = 1_000  # a trial's (and an evaluation episode's) steps when the env sets no time limit


def episode_cap(env, max_steps: int | None = None) -> int:
    """``max_steps`` if given, else the env's own time limit (its spec or a TimeLimit wrapper), else
    ``MAX_EPISODE_STEPS``."""
    if max_steps is not None:
        if isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1:
            raise ValueError(f"max_episode_steps must be a whole number >= 1 or None, got {max_steps!r}")
        return max_steps
    spec = getattr(env, "spec", None)
    if getattr(spec, "max_episode_steps", None):
        return int(spec.max_episode_steps)
    e = env
    while e is not None:
        if isinstance(e, gym.wrappers.TimeLimit):
            return int(e._max_episode_steps)
        e = getattr(e, "env", None)
    return MAX_EPISODE_STEPS
