"""Ch. 7 experiments: determinism of a cup run and a tiny run of every experiment."""

import dataclasses
import json

import numpy as np
import pytest

from connrl.experiments import hidden_state as hs
from connrl.experiments.registry import get_experiment


def test_run_cup_is_deterministic():
    p = dataclasses.replace(hs.CupParams(), arch="recurrent-model", trials=4, lessons_per_trial=3,
                            model_lessons_per_trial=3, task=3)
    a = hs.run_cup(p, np.random.default_rng(7))
    b = hs.run_cup(p, np.random.default_rng(7))
    assert a.curve_y == b.curve_y and a.rows == b.rows
    assert all(14 <= y <= 60 for y in a.curve_y)


@pytest.mark.parametrize("name", [s.name for s in hs.EXPERIMENTS])
def test_tiny_run(tiny_runs, name):
    out = tiny_runs(name)
    summary = json.loads((out / name / "summary.json").read_text())
    assert set(summary["variants"]) == {v.label for v in get_experiment(name).variants}


def test_model_error_of_a_blank_model_by_hand():
    from connrl.core.lessons import Lesson
    from connrl.tasks.hidden_state import make_agent
    agent = make_agent(hs.CupParams(arch="recurrent-model"), 4, 3, np.random.default_rng(0))
    agent.model.w1[...] = 0.0
    agent.model.w2[...] = 0.0  # every output 0: predicts every bit off, payoff 0
    on, off = 0.5, -0.5
    inputs = np.array([[off, off, off, off], [on, off, off, off], [off, off, off, off]])
    lesson = Lesson(inputs, np.array([0, 2]), np.array([0.0, 1.0]), terminated=True)
    err = agent.model_error(lesson)
    # targets: step 0 -> [on, off, off, off] (1 bit of 4 wrong), step 1 -> all off (right); payoffs 0 and 1
    assert err == {"model_wrong_steps": 0.5, "model_wrong_bits": 1 / 8, "model_payoff_error": 0.5}


def test_recurrent_model_rows_carry_the_model_error_of_each_new_lesson():
    p = hs.CupParams(arch="recurrent-model", trials=3, lessons_per_trial=2, model_lessons_per_trial=2, probe=False)
    rows = hs.run_cup(p, np.random.default_rng(0)).rows
    assert all(0 <= r["model_wrong_steps"] <= 1 and r["model_wrong_bits"] <= r["model_wrong_steps"] for r in rows)
    q_rows = hs.run_cup(dataclasses.replace(p, arch="window-Q"), np.random.default_rng(0)).rows
    assert not any("model_wrong_steps" in r for r in q_rows)


def test_frozen_model_stops_learning_at_freeze_at(monkeypatch):
    from connrl.agents.memory import RecurrentModelQ
    seen = []
    train = RecurrentModelQ.train_model

    def spy(self):
        before = self.model.w1.copy()
        out = train(self)
        seen.append((self.freeze_model, not np.array_equal(before, self.model.w1)))
        return out

    monkeypatch.setattr(RecurrentModelQ, "train_model", spy)
    p = hs.FrozenModelParams(task=2, arch="recurrent-model", trials=4, lessons_per_trial=2, model_lessons_per_trial=2,
                             probe=False, freeze_at=2)
    hs.run_cup(p, np.random.default_rng(0))
    assert seen == [(False, True), (False, True), (True, False), (True, False)]  # (frozen, weights changed)
    with pytest.raises(ValueError, match="freeze_at / freeze_after_optimal need arch 'recurrent-model'"):
        dataclasses.replace(p, arch="window-Q").check_combination()


def test_model_is_fixed_at_the_first_optimal_test(monkeypatch):
    from connrl.agents.memory import RecurrentModelQ
    seen = []
    train = RecurrentModelQ.train_model
    monkeypatch.setattr(RecurrentModelQ, "train_model", lambda self: seen.append(self.freeze_model) or train(self))
    def run(p):
        scores = iter([20, 14, 20, 20])  # greedy test scores after trials 1-4: optimal (14) once, after trial 2
        monkeypatch.setattr(hs.cup_play, "test_score", lambda env, agent: next(scores))
        return hs.run_cup(p, np.random.default_rng(0))

    p = hs.FrozenModelParams(task=2, arch="recurrent-model", trials=4, lessons_per_trial=2, model_lessons_per_trial=2,
                             probe=False, freeze_after_optimal=1)
    assert run(p).metrics["frozen_after"] == 2 and seen == [False, False, True, True]
    assert run(dataclasses.replace(p, freeze_after_optimal=2)).metrics["frozen_after"] is None  # 14 only once


def test_unfrozen_variant_is_the_plain_task2_run():
    base = dict(task=2, arch="recurrent-model", lam=0.8, trials=3, lessons_per_trial=2, model_lessons_per_trial=2,
                probe=False)
    a = hs.run_cup(hs.CupParams(**base), np.random.default_rng(3))
    b = hs.run_cup(hs.FrozenModelParams(**base, freeze_at=None), np.random.default_rng(3))
    assert a.curve_y == b.curve_y and a.rows == b.rows


def test_recurrent_model_is_probed_on_random_walks_every_50_trials():
    p = hs.CupParams(arch="recurrent-model", trials=50, lessons_per_trial=1, model_lessons_per_trial=1, probe=False)
    rows = hs.run_cup(p, np.random.default_rng(0)).rows
    assert [r["trial"] for r in rows if "probe_wrong_steps" in r] == [50]
    assert 0 < rows[-1]["probe_wrong_steps"] < 1 and rows[-1]["probe_cup_after_unseen_n"] > 0


def test_the_window_size_experiment_changes_only_the_window():
    from connrl.experiments.hidden_state import CupParams
    from connrl.experiments.registry import get_experiment
    from connrl.tasks.hidden_state import table_entry
    spec = get_experiment("cup-window")
    n5, n2, s5, s2 = (spec.variant_params(spec.params, v) for v in spec.variants)
    assert table_entry(n5)["window"] == 5 and table_entry(n2)["window"] == 2  # Table B.1: N = 5 for Task 1
    t5, t2 = table_entry(n5), table_entry(n2)
    assert {k: v for k, v in t5.items() if k != "window"} == {k: v for k, v in t2.items() if k != "window"}
    assert table_entry(CupParams(task=1, arch="window-Q", lam=0.8)) == t5  # N = 5 is cup-task1's window-Q
    # the same pair again at Table B.1's own 1/T schedule (issue 42): only the schedule differs
    assert (s5.window_q_inv_t, s2.window_q_inv_t) == (None, None) and n5.window_q_inv_t == (5.0, 30.0)
    assert table_entry(s5)["inv_t"] == table_entry(s2)["inv_t"] == (10.0, 30.0) and t5["inv_t"] == (5.0, 30.0)
    assert {k: v for k, v in table_entry(s5).items() if k != "inv_t"} == {k: v for k, v in t5.items() if k != "inv_t"}
