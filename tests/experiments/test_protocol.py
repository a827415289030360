"""The train-and-test loop every experiment shares: the exact order of training trials, tests and progress."""

from types import SimpleNamespace

import pytest

from connrl.experiments.protocol import train_and_test


def record(trials, *, results=None, **kw):
    """Run the loop with logging train/test/progress; ``results(n)`` is what test(n) returns."""
    log = []

    def train(k):
        log.append(("train", k))
        return SimpleNamespace(steps=1, total_reward=0.0)

    def test(n):
        log.append(("test", n))
        return results(n) if results else None

    returned = train_and_test(trials, train, test, progress=lambda done, total: log.append(("progress", done, total)),
                              **kw)
    return returned, log


def events(log):
    """The log without progress calls, as short strings: 'tr0' = train(0), 'te2' = test(2)."""
    return [("tr" if e[0] == "train" else "te") + str(e[1]) for e in log if e[0] != "progress"]


def test_default_tests_after_every_trial():
    returned, log = record(3)
    assert returned == 3
    assert log == [("train", 0), ("test", 1), ("progress", 1, 3),
                   ("train", 1), ("test", 2), ("progress", 2, 3),
                   ("train", 2), ("test", 3), ("progress", 3, 3)]


@pytest.mark.parametrize("kw, expected", [
    ({"test_every": 2, "test_first": True}, ["te0", "tr0", "tr1", "te2", "tr2", "tr3", "te4", "tr4", "te5"]),
    ({"test_every": 2, "test_first": True, "test_last": False}, ["te0", "tr0", "tr1", "te2", "tr2", "tr3", "te4",
                                                                  "tr4"]),
    ({"test_every": 2}, ["tr0", "tr1", "te2", "tr2", "tr3", "te4", "tr4", "te5"]),
    ({"test_every": 2, "test_last": False}, ["tr0", "tr1", "te2", "tr2", "tr3", "te4", "tr4"]),
    ({"test_every": 3, "test_first": True}, ["te0", "tr0", "tr1", "tr2", "te3", "tr3", "tr4", "te5"]),
    ({"test_every": 5, "test_first": True}, ["te0", "tr0", "tr1", "tr2", "tr3", "tr4", "te5"]),  # no double test
    ({"test_every": 7}, ["tr0", "tr1", "tr2", "tr3", "tr4", "te5"]),  # only the last
    ({"test_every": 7, "test_last": False}, ["tr0", "tr1", "tr2", "tr3", "tr4"]),
    ({"test_every": 0, "test_first": True, "test_last": False}, ["te0", "tr0", "tr1", "tr2", "tr3", "tr4"]),
    ({"test_every": 0, "test_last": False}, ["tr0", "tr1", "tr2", "tr3", "tr4"]),  # survival-eval
])
def test_order_of_trials_and_tests(kw, expected):
    returned, log = record(5, **kw)
    assert returned == 5
    assert events(log) == expected
    assert [e for e in log if e[0] == "progress"] == [("progress", n, 5) for n in range(1, 6)]


def test_robot_protocol_tests_before_learning_and_every_test_every_trials():
    # Ch. 5 (5.4): a test before the first trial and after every 10; 30 trials -> tests at 0, 10, 20, 30
    _, log = record(30, test_every=10, test_first=True)
    assert [e[1] for e in log if e[0] == "test"] == [0, 10, 20, 30]
    assert [e[1] for e in log if e[0] == "train"] == list(range(30))


def test_stop_ends_the_loop_after_the_first_test_that_says_so():
    returned, log = record(10, results=lambda n: n >= 3, stop=bool)
    assert returned == 3
    assert log == [("train", 0), ("test", 1), ("progress", 1, 10),
                   ("train", 1), ("test", 2), ("progress", 2, 10),
                   ("train", 2), ("test", 3), ("progress", 3, 10)]


def test_stop_is_asked_only_after_tests():
    returned, log = record(10, results=lambda n: n >= 4, stop=bool, test_every=3)
    assert returned == 6  # trial 4 would pass, but the next test is after trial 6
    assert events(log) == ["tr0", "tr1", "tr2", "te3", "tr3", "tr4", "tr5", "te6"]


def test_stop_never_true_trains_every_trial():
    returned, log = record(4, results=lambda n: False, stop=bool, test_every=2, test_first=True)
    assert returned == 4
    assert events(log) == ["te0", "tr0", "tr1", "te2", "tr2", "tr3", "te4"]


def test_the_test_before_training_does_not_stop_the_loop():
    returned, log = record(5, results=lambda n: True, stop=bool, test_first=True)
    assert returned == 1
    assert events(log) == ["te0", "tr0", "te1"]


def test_stop_at_the_last_trial():
    returned, log = record(3, results=lambda n: n == 3, stop=bool)
    assert returned == 3
    assert events(log) == ["tr0", "te1", "tr1", "te2", "tr2", "te3"]


def test_zero_trials():
    assert record(0) == (0, [])
    assert record(0, test_first=True) == (0, [("test", 0)])
