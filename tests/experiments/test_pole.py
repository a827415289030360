"""Pole balancing experiments (7.5.4 fn. 4): the until-satisfactory protocol and its curve, determinism."""

from dataclasses import replace

import numpy as np

from connrl.core.rollout import TrialStats
from connrl.experiments import pole
from connrl.experiments.pole import EXPERIMENTS, PoleParams, run_pole, train_until_satisfactory


def test_train_until_satisfactory_stops_at_the_first_satisfactory_test(monkeypatch):
    log = []

    def fake_trial(env, agent, *, trial, learning, **kw):
        log.append(("train", trial))
        return TrialStats(steps=10 + trial, total_reward=0.0, terminated=True, truncated=False)

    def fake_satisfactory(env, agent, test_steps):
        log.append(("test", test_steps))
        return sum(e[0] == "test" for e in log) == 3

    monkeypatch.setattr(pole, "run_trial", fake_trial)
    monkeypatch.setattr(pole, "satisfactory", fake_satisfactory)
    progress = []
    r = train_until_satisfactory(None, None, None, 5, 77, lambda d, t: progress.append((d, t)))
    assert log == [("train", 0), ("test", 77), ("train", 1), ("test", 77), ("train", 2), ("test", 77)]
    assert r.metrics == {"trials_to_satisfactory": 3}
    assert r.curve_x == [1, 2, 3, 4, 5] and r.curve_y == [0.0, 0.0, 1.0, 1.0, 1.0]
    assert [row["satisfactory"] for row in r.rows] == [False, False, True]
    assert r.rows[0] == {"trial": 1, "train_steps": 10, "train_failed": True, "satisfactory": False}
    assert progress[-1] == (5, 5)


def test_never_satisfactory_is_none_and_a_flat_curve(monkeypatch):
    monkeypatch.setattr(pole, "run_trial", lambda *a, **k: TrialStats(1, 0.0, True, False))
    monkeypatch.setattr(pole, "satisfactory", lambda *a: False)
    r = train_until_satisfactory(None, None, None, 4, 10, lambda d, t: None)
    assert r.metrics == {"trials_to_satisfactory": None} and r.curve_y == [0.0] * 4 and len(r.rows) == 4


def test_tiny_runs_are_deterministic():
    spec = next(s for s in EXPERIMENTS if s.name == "pole-full")
    p = replace(spec.resolve("tiny")[0], max_trials=2)
    a, b = run_pole(p, np.random.default_rng(3)), run_pole(p, np.random.default_rng(3))
    assert a.rows == b.rows and a.metrics == b.metrics and len(a.curve_x) == 2
    ahc = next(s for s in EXPERIMENTS if s.name == "pole-full-ahc")
    assert ahc.params == replace(PoleParams(), p_threshold=0.2, p_threshold_oldest=None)
    assert run_pole(replace(ahc.resolve("tiny")[0], agent="ahcon", max_trials=2), np.random.default_rng(3)).rows
