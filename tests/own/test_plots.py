"""`connrl plot` over several `connrl train` runs (connrl.own.plots): each run's curve (its evaluations, else its
smoothed training returns), read at common steps by hand-checkable rules, and the figure written."""

import csv

import numpy as np
import pytest

from connrl import cli
from connrl.own.callbacks import LOG_COLUMNS
from connrl.own.plots import SMOOTH, run_curve, runs_at


def test_runs_are_read_at_common_steps_holding_their_latest_value():
    a = (np.array([10.0, 20.0, 30.0]), np.array([1.0, 2.0, 3.0]))
    b = (np.array([15.0, 25.0]), np.array([5.0, 7.0]))
    grid = np.array([5.0, 10.0, 15.0, 20.0, 25.0, 30.0])
    got = runs_at([a, b], grid)
    want = np.array([[np.nan, 1, 1, 2, 2, 3], [np.nan, np.nan, 5, 5, 7, np.nan]])
    np.testing.assert_array_equal(got, want)


def _rows(returns, evals=None):
    rows, steps = [], 0
    for k, r in enumerate(returns):
        steps += 10
        e = None if evals is None else evals.get(k)
        rows.append({"steps": steps, "trial": k + 1, "return": r, "length": 10, "temperature": 1.0, "seconds": k,
                     "eval_mean": e, "eval_std": 0.0 if e is not None else None, "eval_min": e})
    return rows


def test_a_run_is_its_evaluations_else_its_smoothed_returns():
    xs, ys, kind = run_curve(_rows([1.0, 2.0, 3.0], {1: 50.0}))
    assert xs.tolist() == [20.0] and ys.tolist() == [50.0] and kind == "greedy evaluation"
    returns = [float(k) for k in range(SMOOTH + 3)]
    xs, ys, kind = run_curve(_rows(returns))
    assert ys[0] == 0.0 and ys[2] == 1.0 and ys[-1] == np.mean(returns[-SMOOTH:]) and kind.startswith("training")


def _write(folder, rows):
    folder.mkdir(parents=True)
    with open(folder / "progress.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(LOG_COLUMNS)
        for r in rows:
            w.writerow(["" if r[c] is None else r[c] for c in LOG_COLUMNS])


def test_connrl_plot_draws_several_runs_and_refuses_a_folder_without_a_log(tmp_path, capsys):
    for seed in range(3):
        _write(tmp_path / "runs" / f"cp-seed{seed}", _rows([float(seed + k) for k in range(30)]))
    folders = [str(tmp_path / "runs" / f"cp-seed{s}") for s in range(3)]
    assert cli.main(["plot", *folders]) == 0
    out = tmp_path / "runs" / "curves.png"
    assert capsys.readouterr().out.strip() == str(out) and out.read_bytes()[:4] == b"\x89PNG"
    assert cli.main(["plot", *folders[:2], "--to", str(tmp_path / "two.png")]) == 0
    assert (tmp_path / "two.png").exists()
    with pytest.raises(SystemExit, match="holds no progress.csv"):
        cli.main(["plot", folders[0], str(tmp_path)])
