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
