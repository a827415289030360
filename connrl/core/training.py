"""The one training loop, and its callback hooks: every thesis experiment and ``Agent.learn`` on an own task train
through ``train``.

A trial is the unit of learning here: connrl's learners change their nets when a trial ends (replay, 3.5), so the
hooks run between trials (Stable-Baselines3's ``BaseCallback`` runs after any step). What a trial is, is the
caller's: ``play(k, left)`` plays and learns training trial k within ``left`` steps. What happens between trials is
the callbacks': the thesis's greedy tests (``connrl.experiments.protocol``), the divergence check
(``connrl.core.divergence.DivergenceCheck``), evaluation, checkpoints and logs for own tasks (``connrl.own.callbacks``).
"""

from __future__ import annotations

from collections.abc import Callable


class Callback:
    """Hooks of ``train``; subclasses override what they need."""

    def on_training_start(self, agent, total: int) -> None:
        """Before the first trial; ``total`` is the budget: the trials of a thesis run, the steps of ``learn``."""

    def on_trial_end(self, agent, stats) -> bool | None:
        """After each training trial (``stats``: connrl.core.rollout.TrialStats); False stops training."""
        return True

    def on_training_end(self, agent) -> None:
        """After the last trial, also when a callback stopped training."""


class _Function(Callback):
    def __init__(self, fn):
        self.fn = fn

    def on_trial_end(self, agent, stats):
        return self.fn(agent, stats.total_reward)


class CallbackList(Callback):
    """Several callbacks in order; training stops when any returns False (the later ones still run)."""

    def __init__(self, callbacks):
        self.callbacks = [as_callback(c) for c in callbacks]

    def on_training_start(self, agent, total):
        for c in self.callbacks:
            c.on_training_start(agent, total)

    def on_trial_end(self, agent, stats):
        go = [c.on_trial_end(agent, stats) is not False for c in self.callbacks]
        return all(go)

    def on_training_end(self, agent):
        for c in self.callbacks:
            c.on_training_end(agent)


def as_callback(callback) -> Callback:
    """A Callback from None, a Callback, a function ``f(agent, trial_return)`` or a list of these."""
    if callback is None:
        return Callback()
    if isinstance(callback, Callback):
        return callback
    if isinstance(callback, (list, tuple)):
        return CallbackList(callback)
    if callable(callback):
        return _Function(callback)
    raise ValueError(f"callback must be a connrl Callback, a function (agent, trial_return) or a list of them, got "
                     f"{type(callback).__name__}")


def train(play: Callable[[int, int | None], object], callback=None, *, agent=None, trials: int | None = None,
          steps: int | None = None) -> tuple[int, int]:
    """Train trial after trial: ``play(k, left)`` plays and learns training trial k (k = 0, 1, ...) within ``left``
    steps (None without a step budget) and returns its TrialStats; the callbacks run after each. Stops after
    ``trials`` trials or ``steps`` steps (whichever is given; both: the first reached), or when a callback returns
    False. ``agent`` is what the hooks are given. Returns (trials, steps) trained."""
    if trials is None and steps is None:
        raise ValueError("train needs a budget: trials, steps or both")
    callbacks = as_callback(callback)
    callbacks.on_training_start(agent, trials if steps is None else steps)
    k = done = 0
    while (trials is None or k < trials) and (steps is None or done < steps):
        stats = play(k, None if steps is None else steps - done)
        k += 1
        done += stats.steps
        if callbacks.on_trial_end(agent, stats) is False:
            break
    callbacks.on_training_end(agent)
    return k, done
