"""One trial of the agent protocol in any Gymnasium environment: the thesis's training trial or test trial.

Training (``learning=True``): stochastic actions, the agent observes each step (on-line learning, Figs. 3.2
and 3.4) and replays after the trial (3.5). Test (``learning=False``): the greedy policy (T = 0), nothing
learned. ``terminated`` and ``truncated`` stay distinct: a timeout is not a failure.
"""

from __future__ import annotations

from dataclasses import dataclass, field


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
    ``max_steps`` stops a test early (counted as truncated); ``on_step(info)`` sees every step.
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
        if learning:
            agent.observe(a, r, obs, terminated, truncated, info)
        if on_step is not None:
            on_step(info)
        if terminated or truncated:
            break
        if max_steps is not None and steps >= max_steps:
            truncated = True
            break
    agent.end_trial()
    if learning:
        agent.learn()
    return TrialStats(steps, total, bool(terminated), bool(truncated), info)
