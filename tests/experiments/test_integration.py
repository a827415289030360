"""Ch. 8's experiments: refusals, the doorway regions of the probe by hand, a tiny run's records (probe, changed-
layout paths) and determinism, and the 8.5 table's "good" criterion by hand."""

import numpy as np
import pytest

from connrl.envs.robot import Layout
from connrl.experiments.integration import IntegrationParams, _near_door, run_integration
from connrl.experiments.steps import steps_to_good

TINY = dict(trials=2, test_every=1, tests_per_room=1, lessons_per_trial=2, max_steps=20, final_tests_per_room=2,
            probe_samples=50)


@pytest.mark.parametrize("kw, message", [
    ({"memory": "lstm"}, "memory must be one of"),
    ({"memory": "recurrent", "hidden": 4, "context": 8, "online": False}, "context must be at most hidden"),
    ({"pretrain_steps": 300}, "not built for Ch. 8"),
    ({"memory": "recurrent", "hidden": 12}, "online must be False"),
    ({"share_output": True}, "share_output applies to memory='recurrent' only"),
    ({"memory": "recurrent", "grouping": True, "online": False}, "not built for Ch. 8")])
def test_bad_parameters_are_refused(kw, message):
    with pytest.raises(ValueError, match=message):
        IntegrationParams(**kw)


def test_legs_of_a_trial_by_hand():
    from connrl.experiments.integration import _legs
    L = Layout.load("default")
    b, c, a = (300.0, 60.0, 0.0), (246.0, 330.0, 0.0), (60.0, 100.0, 0.0)
    assert _legs(L, [b, c, b, b, c, c, b]) == (True, False, 2)  # out into C and back through door B twice
    assert _legs(L, [b, c, a]) == (True, True, 0) and _legs(L, [b, b]) == (False, False, 0)


def test_near_door_regions_by_hand():
    L = Layout.load("default")  # subgoal 4 (114, 330) in front of door A, 5 (246, 330) in front of door B
    assert _near_door(L, (114.0, 330.0, 90.0)) == "A" and _near_door(L, (246.0, 355.0, 0.0)) == "B"
    assert _near_door(L, (246.0, 361.0, 0.0)) is None  # 31 in away
    assert _near_door(L, (114.0, 290.0, 90.0)) is None  # 40 in, and in room A, not C
    assert _near_door(L, (180.0, 330.0, 0.0)) is None  # between the doors


@pytest.mark.parametrize("memory", ["none", "recurrent"])
def test_a_tiny_run_keeps_the_final_tests_the_probe_and_the_changed_paths(memory):
    p = IntegrationParams(memory=memory, hidden=12, online=memory == "none", **TINY)
    a, b = run_integration(p, np.random.default_rng(3)), run_integration(p, np.random.default_rng(3))
    assert a.curve_y == b.curve_y and a.metrics == b.metrics and a.extra == b.extra  # deterministic
    assert [r["trials"] for r in a.rows] == [0, 1, 2] and a.rows[-1]["train_steps"] == a.metrics["train_steps"]
    for layout in ("default", "changed"):
        for room in "ABC":
            assert a.metrics[f"{layout}_docked_{room}"] in (0.0, 0.5, 1.0)
    paths = a.extra["changed_paths"]
    assert [q["room"] for q in paths] == ["A", "B", "C"]
    changed = Layout.load("changed")
    assert all(changed.room_at(*q["poses"][0][:2]) == q["room"] for q in paths)  # drawn in the changed layout
    for s in a.extra["probe"]:
        assert s["door"] in "AB" and len(s["x"]) == 14 and len(s["q"]) == 4
        assert ("context" in s) == (memory == "recurrent") and len(s.get("context", [0] * 8)) == 8


def test_steps_to_good_by_hand():
    def run(perf, steps):
        return [{"trials": 10.0 * k, "performance": p, "train_steps": s}
                for k, (p, s) in enumerate(zip(perf, steps, strict=True))]

    runs = [run([0, 1, 2, 3, 3], [0, 100, 200, 300, 400]), run([0, 3, 4, 5, 5], [0, 50, 150, 250, 350])]
    # mean curve 0, 2, 3, 4, 4; final level (3 + 4 + 4) / 3 = 11/3; 90 % of the way from 0 is 3.3: first at trial 30
    assert steps_to_good(runs) == (30.0, 275.0)
    assert steps_to_good(runs, fraction=0.5) == (10.0, 75.0)  # 1.83: the mean curve's 2 at trial 10
    assert steps_to_good([run([1, 1, 1, 1], [0, 1, 2, 3])]) == (None, None)  # no learning: no "good" to reach
    assert steps_to_good([]) == (None, None)


def test_the_probe_records_the_inputs_q_values_and_context_each_choice_read(monkeypatch):
    # every step counts as near door A here; the records must equal an independent replay of the trial by the same
    # nets from a zero context: c_t (before the chosen net advances it) and Q(x_t, c_t)
    from connrl.experiments import integration
    from connrl.tasks.integration import make_integration_agent, make_integration_env

    p = IntegrationParams(memory="recurrent", hidden=12, online=False, **TINY)
    agent = make_integration_agent(p, np.random.default_rng(0))
    env = make_integration_env(p)
    monkeypatch.setattr(integration, "_near_door", lambda layout, pose: "A")
    probe = []
    integration.greedy_trial(env, agent, (246.0, 330.0, 90.0), seed=1, probe=probe, trial_id=7)
    assert len(probe) == 20 and {s["trial"] for s in probe} == {7} and probe[0]["start_room"] == "C"
    xs, acts = np.array([s["x"] for s in probe]), np.array([s["behaviour"] for s in probe])
    ys, cs = agent.net.forward_sequence(xs, acts)
    np.testing.assert_allclose([s["context"] for s in probe], cs[:-1], atol=1e-3)
    np.testing.assert_allclose([s["q"] for s in probe], ys[:, :, 0], atol=2e-3)
    assert np.abs(cs[1:-1]).max() > 0.01  # the context did move
