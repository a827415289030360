"""The Ch. 6 behaviour library: exact round trip, refusals of wrong files, applicability thresholds, the shipped
library, and deterministic training."""

from __future__ import annotations

import json

import numpy as np
import pytest

from connrl.experiments.behaviours import TrainingPlan, train_behaviour, train_library
from connrl.nets import OAON, NetConfig
from connrl.tasks.behaviours import (
    APPLICABLE_ABOVE,
    Behaviour,
    library_paths,
    load_behaviour,
    load_library,
    save_behaviour,
)


def random_behaviour(task="DP", n_in=52, seed=0):
    return Behaviour(task, OAON(NetConfig(n_in, 16, value_range=100.0, init_range=0.5), 6,
                                np.random.default_rng(seed)), -0.5, {"seed": seed})


def test_round_trip_is_exact(tmp_path):
    b = random_behaviour()
    save_behaviour(b, tmp_path / "dp")
    c = load_behaviour(tmp_path / "dp", "DP")
    np.testing.assert_array_equal(c.q.w1, b.q.w1)
    np.testing.assert_array_equal(c.q.w2, b.q.w2)
    x = np.random.default_rng(1).uniform(-0.5, 1, 52)
    assert c.q_values(x).tolist() == b.q_values(x).tolist() and c.act(x) == b.act(x)
    assert (c.task, c.binary_low, c.meta) == ("DP", -0.5, {"seed": 0})


def test_wrong_files_are_refused_with_one_line(tmp_path):
    save_behaviour(random_behaviour(), tmp_path / "dp")
    with pytest.raises(ValueError, match="task: is 'DP'; this file must hold behaviour DK"):
        load_behaviour(tmp_path / "dp", "DK")
    with pytest.raises(ValueError, match="no such behaviour file"):
        load_behaviour(tmp_path / "missing")
    meta = json.loads((tmp_path / "dp.json").read_text())
    (tmp_path / "bad.json").write_text(json.dumps({**meta, "n_inputs": 36}))
    (tmp_path / "bad.npz").write_bytes((tmp_path / "dp.npz").read_bytes())
    with pytest.raises(ValueError, match="n_inputs: is 36; it must be a whole number >= 52 and <= 52"):
        load_behaviour(tmp_path / "bad")
    (tmp_path / "short.json").write_text(json.dumps(meta))
    np.savez(tmp_path / "short.npz", w1=np.zeros((6, 16, 10)), w2=np.zeros((6, 17)))
    with pytest.raises(ValueError, match=r"w1: has shape \(6, 16, 10\); it must have shape \(6, 16, 53\)"):
        load_behaviour(tmp_path / "short")
    (tmp_path / "obj.json").write_text(json.dumps(meta))
    np.savez(tmp_path / "obj.npz", w1=np.array([{"a": 1}], dtype=object), w2=np.zeros((6, 17)))
    with pytest.raises(ValueError, match="holds object data"):  # pickled objects are never loaded
        load_behaviour(tmp_path / "obj")
    (tmp_path / "other.json").write_text(json.dumps({**meta, "kind": "something else"}))
    with pytest.raises(ValueError, match="not a connrl behaviour file"):
        load_behaviour(tmp_path / "other")


class FixedQ:
    n_nets = 6

    def __init__(self, top):
        self.top = top

    def values(self, x):
        return np.array([0.0, self.top, -5.0, 0.0, 0.0, 0.0])


@pytest.mark.parametrize("task, top, applies", [("DP", 30.5, True), ("DP", 30.0, False), ("DK", 25.5, True),
                                                ("DK", 24.0, False), ("WFL", -99.0, True), ("WFR", -99.0, True)])
def test_applicability_thresholds_of_6_4_3(task, top, applies):
    assert Behaviour(task, FixedQ(top)).applicable(np.zeros(3)) is applies
    assert APPLICABLE_ABOVE["DP"] == 30 and APPLICABLE_ABOVE["DK"] == 25


def test_shipped_library_loads_and_records_its_provenance():
    lib = load_library()
    assert set(lib) == {"DK", "DP", "WFL", "WFR"}
    index = json.loads((library_paths()["DK"].parent / "library.json").read_text())["behaviours"]
    for task, b in lib.items():
        assert b.meta["trials"] == 1500 and b.meta["code"]["connrl"] and index[task]["seed"] == b.meta["seed"]
    assert lib["DP"].meta["far_share"] == lib["DK"].meta["far_share"] == 0.25 and lib["WFL"].meta["lessons"] == 5


def test_training_is_deterministic_and_a_library_round_trips(tmp_path):
    a = train_behaviour(TrainingPlan("DP", trials=3, far_share=0.5), seed=4)
    b = train_behaviour(TrainingPlan("DP", trials=3, far_share=0.5), seed=4)
    np.testing.assert_array_equal(a.q.w1, b.q.w1)
    index = train_library(tmp_path, seed=7, trials=2, workers=1)
    assert set(index) == {"DK", "DP", "WFL", "WFR"} and [index[t]["seed"] for t in ("DK", "DP", "WFL", "WFR")] == \
        [7, 8, 9, 10]
    assert all(0.0 <= m["serve_rate"] <= 1.0 for m in index.values())
    assert load_library(tmp_path)["WFR"].task == "WFR"


class FrontSonarQ:
    """Q = 100 x the encoded reading straight ahead, for every action: the map is then computable by hand."""

    n_nets = 6

    def values(self, x):
        return np.full(6, 100.0 * x[0])


def test_q_value_map_is_the_max_over_headings_and_nan_where_the_robot_does_not_fit():
    from connrl.envs.robot import Layout, RobotSim, encode_sonar
    from connrl.tasks.behaviours import q_value_map

    layout = Layout.load("default")
    xs, ys, grid = q_value_map(Behaviour("DP", FrontSonarQ()), layout, spacing=60.0)
    assert grid.shape == (ys.size, xs.size) == (7, 6)
    sim = RobotSim(layout, np.random.default_rng(0), sensor_noise=False, control_noise=False)
    for i, y in enumerate(ys):
        for j, x in enumerate(xs):
            if not layout.is_free(x, y):
                assert np.isnan(grid[i, j])
                continue
            best = -np.inf
            for h in (0.0, 90.0, 180.0, 270.0):
                sim.place(x, y, h)
                ahead = sim.true_ranges()[:1] + 12.0  # the default world's sonar reads from the centre (issue 44)
                best = max(best, 100.0 * float(encode_sonar(ahead.clip(0, 127))[0]))
            assert grid[i, j] == pytest.approx(best, abs=0.8)  # the scan rounds readings to 1 in


@pytest.mark.parametrize("change, message", [
    ({"value_range": None}, "value_range: is None; it must be a finite number > 0"),
    ({"value_range": "x"}, "value_range: is 'x'; it must be"), ({"binary_low": 5}, "binary_low: is 5; it must be -0.5"),
    ({"provenance": [1]}, "provenance: is list; it must be an object")])
def test_bad_fields_are_one_line(tmp_path, change, message):
    save_behaviour(random_behaviour(), tmp_path / "dp")
    meta = json.loads((tmp_path / "dp.json").read_text())
    (tmp_path / "dp.json").write_text(json.dumps({**meta, **change}))
    with pytest.raises(ValueError, match=message):
        load_behaviour(tmp_path / "dp")


@pytest.mark.parametrize("content", [b"", b"not an archive", "npy"])
def test_unreadable_weight_files_are_one_line(tmp_path, content):
    save_behaviour(random_behaviour(), tmp_path / "dp")
    if content == "npy":
        np.save(tmp_path / "x.npy", np.zeros(3))
        (tmp_path / "dp.npz").write_bytes((tmp_path / "x.npy").read_bytes())
    else:
        (tmp_path / "dp.npz").write_bytes(content)
    with pytest.raises(ValueError, match="not a readable behaviour weight file|is a single .npy array|is not an "
                                         ".npz archive"):
        load_behaviour(tmp_path / "dp")


def test_library_digest_changes_with_any_behaviour_file(tmp_path):
    from connrl.tasks.behaviours import library_digest

    for t, seed in (("DK", 0), ("DP", 1), ("WFL", 2), ("WFR", 3)):
        n_in = 52 if t in ("DK", "DP") else 36
        save_behaviour(random_behaviour(t, n_in, seed), library_paths(tmp_path)[t])
    before = library_digest(tmp_path)
    assert before == library_digest(tmp_path) and len(before) == 12
    save_behaviour(random_behaviour("WFR", 36, 9), library_paths(tmp_path)["WFR"])
    assert library_digest(tmp_path) != before
