"""The non-policy test's probability (3.5.1: Eq. 3.6, or Eq. 6.6 under behaviour weights) is written once in the
compiled kernels, ``kernels._policy_probability``, and every replay kernel calls it; NumPy's
``boltzmann_probabilities`` and ``weighted_boltzmann_probabilities`` are its oracles."""

import ast
from pathlib import Path

import numpy as np
import pytest

from connrl.core.exploration import boltzmann_probabilities, weighted_boltzmann_probabilities
from connrl.nets import kernels

SOURCE = ast.parse(Path(kernels.__file__).read_text())
FUNCTIONS = {n.name: n for n in SOURCE.body if isinstance(n, ast.FunctionDef)}
NONE = np.empty((0, 0))


def _draws(n, seed):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        size = int(rng.integers(1, 8))
        q = rng.normal(0, rng.choice([0.1, 1.0, 40.0]), size)
        if rng.random() < 0.3:
            q[rng.integers(size)] = q.max()  # a tie for the top
        w = rng.choice([0.0, 1.0, 100.0], size)
        w[rng.integers(size)] = 1.0  # not all ruled out
        yield q, w, int(rng.integers(size)), float(rng.choice([0.0, 0.02, 0.5, 3.0]))


def test_eq_3_6_as_numpy_computes_it():
    for q, _, a, t in _draws(3000, seed=1):
        want = boltzmann_probabilities(q, t)[a]
        got = kernels._policy_probability(q, NONE, 0, a, t)
        assert got == want if t == 0 else got == pytest.approx(want, rel=1e-13, abs=1e-300)


def test_eq_6_6_as_numpy_computes_it_on_any_row():
    for q, w, a, t in _draws(3000, seed=2):
        rows = np.vstack([np.ones_like(w), w])  # the weights are read from their row, not the first
        with np.errstate(over="ignore", invalid="ignore"):  # NumPy's where computes the ruled-out choices too
            want = weighted_boltzmann_probabilities(q, w, t)[a]
        got = kernels._policy_probability(q, rows, 1, a, t)
        assert got == want if t == 0 else got == pytest.approx(want, rel=1e-13, abs=1e-300)


def test_hand_cases():
    q = np.array([1.0, 3.0, 3.0, 0.0])
    assert kernels._policy_probability(q, NONE, 0, 1, 0.0) == 0.5  # greedy ties share the mass
    assert kernels._policy_probability(q, NONE, 0, 0, 0.0) == 0.0
    w = np.array([[1.0, 0.0, 1.0, 1.0]])
    assert kernels._policy_probability(q, w, 0, 2, 0.0) == 1.0  # the ruled-out tie takes no share
    assert kernels._policy_probability(q, w, 0, 1, 0.5) == 0.0
    e = np.exp((np.array([1.0, 3.0, 0.0]) - 3.0) / 0.5)
    assert kernels._policy_probability(q, w, 0, 0, 0.5) == pytest.approx(e[0] / e.sum(), rel=1e-15)
    assert kernels._policy_probability(np.array([np.nan, 1.0]), NONE, 0, 0, 0.0) == 0.0  # a NaN merit is no policy


def _divides_by_temperature(fn: ast.FunctionDef) -> bool:
    return any(isinstance(n, ast.BinOp) and isinstance(n.op, ast.Div) and isinstance(n.right, ast.Name)
               and n.right.id == "temperature" for n in ast.walk(fn))


def test_no_other_kernel_writes_a_boltzmann_probability():
    assert [name for name, fn in FUNCTIONS.items() if _divides_by_temperature(fn)] == ["_policy_probability"]


def test_every_replay_with_a_policy_test_calls_it():
    def calls(name):
        nodes = ast.walk(FUNCTIONS[name])
        return {c.func.id for c in nodes if isinstance(c, ast.Call) and isinstance(c.func, ast.Name)}
    callers = {name for name in FUNCTIONS if "_policy_probability" in calls(name)}
    assert callers == {"_replay_mlp", "_replay_q_steps", "_rotated_policy_test", "_policy_weights"}
    assert "_rotated_policy_test" in calls("_replay_rotated_kernel") & calls("_replay_ahc_rotated_kernel")
    assert "_policy_weights" in calls("_replay_recurrent_lesson")
