"""The protocol every experiment shares: the train-and-test loop.

The thesis measures learning the same way in every chapter: training trials (stochastic actions, learning
on; ``connrl.core.run_trial``) interleaved with tests of the greedy policy (T = 0, learning off).
``train_and_test`` is that loop: ``connrl.core.training.train``, the loop ``Agent.learn`` trains own tasks with,
with three callbacks (the divergence check, the tests, the progress report); a chapter supplies what one training
trial and one test are.
"""

from __future__ import annotations

from collections.abc import Callable

from connrl.core.divergence import DivergenceCheck
from connrl.core.training import Callback, train


class Tests(Callback):
    """The thesis's tests between training trials: ``test(n)`` with n the trials trained so far, after every
    ``every``-th trial (0: none), also before the first (``first``) and after the last of ``trials`` (``last``);
    training stops when ``stop(test result)`` is true."""

    def __init__(self, test: Callable[[int], object], trials: int, every: int = 1, first: bool = False,
                 last: bool = True, stop: Callable[[object], bool] | None = None):
        self.test, self.trials, self.every, self.first, self.last, self.stop = test, trials, every, first, last, stop
        self.n = 0

    def on_training_start(self, agent, total):
        if self.first:
            self.test(0)

    def on_trial_end(self, agent, stats):
        self.n += 1
        n = self.n
        if self.every and (n % self.every == 0 or (self.last and n == self.trials)):
            result = self.test(n)
            if self.stop is not None and self.stop(result):
                return False
        return True


class Progress(Callback):
    """``progress(trials done, trials)`` after each training trial."""

    def __init__(self, progress: Callable[[int, int], None], trials: int):
        self.progress, self.trials, self.n = progress, trials, 0

    def on_trial_end(self, agent, stats):
        self.n += 1
        self.progress(self.n, self.trials)
        return True


def train_and_test(trials: int, train_trial: Callable[[int], object], test: Callable[[int], object], *,
                   test_every: int = 1, test_first: bool = False, test_last: bool = True,
                   stop: Callable[[object], bool] | None = None,
                   progress: Callable[[int, int], None] = lambda done, total: None, agent=None) -> int:
    """Train ``trials`` trials (``train_trial(k)``, k = 0..trials-1, returning its TrialStats) with ``Tests(test,
    trials, test_every, test_first, test_last, stop)`` between them (``test_every=0``: no tests after any trial,
    ``test_last`` included). With ``agent``, its networks are checked after every training trial and a diverged run
    stops with ``connrl.core.divergence.Diverged``. Returns the trials trained."""
    callbacks = [DivergenceCheck(agent)] if agent is not None else []
    callbacks += [Tests(test, trials, test_every, test_first, test_last, stop), Progress(progress, trials)]
    trained, _ = train(lambda k, left: train_trial(k), callbacks, agent=agent, trials=trials)
    return trained
