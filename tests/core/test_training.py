"""The one training loop (``connrl.core.training.train``): budgets in trials and in steps, the hooks' order, a
callback's stop, and the divergence check every thesis run's loop starts with."""

from types import SimpleNamespace

import numpy as np
import pytest

from connrl.core.divergence import Diverged, DivergenceCheck
from connrl.core.training import Callback, as_callback, train


class Log(Callback):
    def __init__(self, log, stop_after=None):
        self.log, self.stop_after, self.ends = log, stop_after, 0

    def on_training_start(self, agent, total):
        self.log.append(("start", total))

    def on_trial_end(self, agent, stats):
        self.log.append(("end", stats.steps))
        self.ends += 1
        return self.stop_after is None or self.ends < self.stop_after

    def on_training_end(self, agent):
        self.log.append(("stop",))


def player(lengths, log):
    def play(k, left):
        log.append(("play", k, left))
        return SimpleNamespace(steps=lengths[k] if left is None else min(lengths[k], left), total_reward=float(k))
    return play


def test_a_trial_budget():
    log = []
    assert train(player([3, 4, 5, 6], log), Log(log), trials=3) == (3, 12)
    assert log == [("start", 3), ("play", 0, None), ("end", 3), ("play", 1, None), ("end", 4), ("play", 2, None),
                   ("end", 5), ("stop",)]


def test_a_step_budget_gives_each_trial_what_is_left_and_ends_on_it():
    log = []
    assert train(player([4, 4, 4, 4], log), Log(log), steps=10) == (3, 10)
    assert [e for e in log if e[0] == "play"] == [("play", 0, 10), ("play", 1, 6), ("play", 2, 2)]
    assert log[0] == ("start", 10) and log[-1] == ("stop",)


def test_both_budgets_end_at_the_first_reached():
    assert train(player([4] * 9, []), trials=2, steps=100) == (2, 8)
    assert train(player([4] * 9, []), trials=9, steps=6) == (2, 6)


def test_a_callback_stops_training_and_the_end_hook_still_runs():
    log = []
    assert train(player([1] * 9, log), Log(log, stop_after=2), trials=9) == (2, 2)
    assert log[-1] == ("stop",)


def test_every_callback_of_a_list_runs_on_the_trial_one_stops():
    log, seen = [], []
    callbacks = [Log(log, stop_after=1), lambda agent, ret: seen.append(ret)]
    assert train(player([1] * 5, log), callbacks, trials=5) == (1, 1)
    assert seen == [0.0]


def test_a_budget_is_needed_and_a_callback_must_be_one():
    with pytest.raises(ValueError, match="budget"):
        train(player([1], []))
    with pytest.raises(ValueError, match="callback must be"):
        as_callback(3)


class Net:
    def __init__(self, w):
        self.w = np.array(w)

    def state_dict(self):
        return {"w": self.w}


def test_the_divergence_check_stops_after_the_trial_that_diverged():
    learner = SimpleNamespace(q=Net([1.0, 2.0]))

    def play(k, left):
        if k == 2:
            learner.q.w[1] = np.nan
        return SimpleNamespace(steps=1, total_reward=0.0)

    with pytest.raises(Diverged) as err:
        train(play, [DivergenceCheck(learner)], trials=5)
    assert err.value.trial == 3 and "non-finite weights in q.w" in err.value.reason
