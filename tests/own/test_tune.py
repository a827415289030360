"""`connrl tune`'s search (connrl.own.tune): no setting tried twice (a shuffled grid where the space is a few
choices), trial k's settings independent of the trials asked, the median pruner's bars by hand, parallel trials
giving the serial search's results."""

import itertools
import json
from functools import partial

import gymnasium as gym
import pytest

from connrl import cli
from connrl.own.tune import median_thresholds, parse_dimension, planned, run_search


def test_a_small_space_is_its_grid_shuffled_each_setting_once():
    space = [parse_dimension("lr=0.02,0.1"), parse_dimension("hidden=4:6")]
    plan = planned(space, 50, seed=0)
    grid = [{"lr": lr, "hidden": h} for lr, h in itertools.product((0.02, 0.1), (4, 5, 6))]
    assert len(plan) == 6 and sorted(plan, key=json.dumps) == sorted(grid, key=json.dumps)
    assert planned(space, 2, seed=0) == plan[:2]  # trial k's settings do not depend on the trials asked
    two = planned([parse_dimension("lr=0.02,0.1")], 2, seed=0)
    assert sorted(p["lr"] for p in two) == [0.02, 0.1]  # 2 trials of 2 choices: both, not one twice


def test_a_continuous_space_draws_without_repeats_and_stably():
    space = [parse_dimension("lr=0.01:0.2:log"), parse_dimension("hidden=8,16")]
    plan = planned(space, 30, seed=3)
    assert len({json.dumps(p, sort_keys=True) for p in plan}) == 30
    assert planned(space, 10, seed=3) == plan[:10] and planned(space, 10, seed=4) != plan[:10]
    assert all(0.01 <= p["lr"] <= 0.2 and p["hidden"] in (8, 16) for p in plan)


def _trial(k, scores):
    return {"trial": k, "params": {}, "scores": scores, "mean": sum(scores) / len(scores), "seconds": 0.0}


def test_median_bars_by_hand():
    done = [_trial(0, [10.0, 20.0, 30.0]), _trial(1, [0.0, 4.0, 8.0]), _trial(2, [6.0, 6.0, 6.0]), _trial(3, [2.0])]
    assert median_thresholds(done, 3) == ()  # 3 whole trials (trial 3 was pruned): no bar yet
    done.append(_trial(4, [8.0, 12.0, 1.0]))
    # whole trials' running means after seed 0: 10, 0, 6, 8 -> 7; after seed 1: 15, 2, 6, 10 -> 8
    assert median_thresholds(done, 3) == (7.0, 8.0)


def _study(tmp, **kw):
    return {"env_id": "CartPole-v1", "env_kwargs": {}, "agent": "QCON-R", "steps": 150, "seeds": [1000, 1001],
            "eval_episodes": 1, "trials": 4, "fixed": {"hidden": 4, "warmup_steps": 50},
            "space": ["lr=0.02,0.05,0.1,0.2"], "sampler": "random", "seed": 0, "pruner": "none", "draws": "unrepeated",
            **kw}


def test_parallel_trials_give_the_serial_searchs_results(tmp_path):
    space = [parse_dimension("lr=0.02,0.05,0.1,0.2")]
    env_fn = partial(gym.make, "CartPole-v1")
    serial = run_search(env_fn, _study(tmp_path), space, tmp_path / "a", progress=lambda m: None)
    parallel = run_search(env_fn, _study(tmp_path), space, tmp_path / "b", progress=lambda m: None, workers=2)
    strip = [(t["trial"], t["params"], t["scores"]) for t in serial]
    assert strip == [(t["trial"], t["params"], t["scores"]) for t in parallel]
    assert (tmp_path / "a" / "trials.csv").read_text().splitlines()[0] == "trial,params,scores,mean,seconds"
    assert sorted(t["params"]["lr"] for t in serial) == [0.02, 0.05, 0.1, 0.2]


@pytest.mark.parametrize("extra", [["--workers", "2"], ["--pruner", "median"]])
def test_tpe_refuses_workers_and_the_pruner_in_one_line(tmp_path, extra):
    with pytest.raises(SystemExit, match="--workers and --pruner go with --sampler random"):
        cli.main(["tune", "CartPole-v1", "--sampler", "tpe", *extra, "--out", str(tmp_path / "t")])


def test_a_log_range_of_whole_numbers_is_drawn_not_enumerated():
    from connrl.own.tune import grid_values

    assert grid_values(parse_dimension("hidden=4:8")) == (4, 5, 6, 7, 8)
    assert grid_values(parse_dimension("hidden=4:64:log")) is None


def test_a_trial_below_the_bar_is_pruned_after_that_seed():
    from connrl.own.tune import score

    args = (partial(gym.make, "CartPole-v1"), "QCON-R", {"hidden": 4, "warmup_steps": 50}, [1000, 1001], 100, 1)
    assert len(score(*args, prune_below=(1e9,))) == 1
    assert len(score(*args, prune_below=(-1e9,))) == 2 == len(score(*args))
