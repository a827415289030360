"""The protocol every experiment shares: the train-and-test loop.

The thesis measures learning the same way in every chapter: training trials (stochastic actions, learning
on; ``connrl.core.run_trial``) interleaved with tests of the greedy policy (T = 0, learning off).
``train_and_test`` is that loop; a chapter supplies what one training trial and one test are.
"""

from __future__ import annotations

from collections.abc import Callable

from connrl.core.divergence import Diverged, network_problem


def train_and_test(trials: int, train: Callable[[int], object], test: Callable[[int], object], *,
                   test_every: int = 1, test_first: bool = False, test_last: bool = True,
                   stop: Callable[[object], bool] | None = None,
                   progress: Callable[[int, int], None] = lambda done, total: None, agent=None) -> int:
    """Train ``trials`` trials (``train(k)``, k = 0..trials-1) and test after every ``test_every``-th one
    (``test(n)`` with n the trials trained so far); also before the first (``test_first``) and after the last
    (``test_last``). ``test_every=0`` trains without tests after any trial (``test_last`` included). Stops early
    when ``stop(test result)`` is true. With ``agent``, its networks are checked after every training trial and
    a diverged run stops with ``connrl.core.divergence.Diverged``. Returns the trials trained."""
    if test_first:
        test(0)
    for k in range(trials):
        train(k)
        n = k + 1
        problem = network_problem(agent) if agent is not None else None
        if problem:
            raise Diverged(n, problem)
        if test_every and (n % test_every == 0 or (test_last and n == trials)):
            result = test(n)
            if stop is not None and stop(result):
                progress(n, trials)
                return n
        progress(n, trials)
    return trials
