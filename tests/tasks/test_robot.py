"""Ch. 5 wiring: shipped and regenerated taught lessons, lessons for another geometry, QCON-T's configuration."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from connrl.agents.teaching import TeachingConfig, TeachingQCON
from connrl.core.lesson_files import load_lessons
from connrl.envs.robot import Layout, RobotTaskEnv
from connrl.experiments.robot import RobotParams, run_robot
from connrl.tasks import robot
from connrl.tasks.robot import binary_columns, make_agent, make_taught_lessons, taught_lessons


def test_taught_lessons_shipped_and_reencoded():
    dp = taught_lessons("DP", 10)
    assert len(dp) == 10 and all(lesson.taught and lesson.terminated for lesson in dp)
    assert all(lesson.rewards[-1] == 100.0 for lesson in dp)  # positive examples (5.4.1)
    assert len(taught_lessons("DK", 3)) == 3 and len(taught_lessons("WFL", 5)) == 5
    cols = binary_columns("DP")
    assert set(np.unique(dp[0].inputs[:, cols])) <= {-0.5, 0.5}
    zero_one = taught_lessons("DP", 1, binary_low=0.0)[0]
    assert set(np.unique(zero_one.inputs[:, cols])) <= {0.0, 1.0}
    np.testing.assert_array_equal(zero_one.inputs[:, :24], dp[0].inputs[:, :24])  # sonar untouched
    wf = taught_lessons("WFL", 1, binary_low=0.0)[0]
    np.testing.assert_array_equal(wf.inputs[:, 28:30], taught_lessons("WFL", 1)[0].inputs[:, 28:30])
    # more lessons than the file has: the teacher demonstrates afresh, the first ones are the file's
    more = taught_lessons("DP", 12)
    assert len(more) == 12 and all(lesson.rewards[-1] == 100.0 for lesson in more)
    for a, b in zip(more[:10], dp, strict=True):
        np.testing.assert_array_equal(a.inputs, b.inputs)


def test_agent_config_matches_thesis():
    agent = make_agent(RobotParams(task="DP", lessons=3), np.random.default_rng(0))
    c = agent.config
    assert (c.net.n_inputs, c.net.n_hidden, c.net.lr, c.net.momentum, c.net.init_range) == (52, 16, 0.05, 0.9, 0.5)
    assert c.net.value_range == 100.0 and c.gamma == 0.9 and c.lam == 0.7
    assert c.temperature(0) == pytest.approx(0.05) and c.temperature(299) == pytest.approx(0.02)
    assert len(agent.book.taught) == 3
    wf = make_agent(RobotParams(task="WFL", lessons=0, hidden_fraction=0.0), np.random.default_rng(0))
    assert wf.config.net.n_hidden == 0 and wf.config.net.n_inputs == 36
    with pytest.raises(ValueError, match="repair must be one of"):
        TeachingConfig(repair="up")
    assert isinstance(agent, TeachingQCON)


def test_other_geometry_gets_its_own_taught_lessons():
    wide = robot.taught_lessons("DP", 3, -0.5, door_width=36.0, edge_jump=24.0)
    again = robot.taught_lessons("DP", 3, -0.5, door_width=36.0, edge_jump=24.0)
    shipped = robot.taught_lessons("DP", 3)
    for a, b in zip(wide, again, strict=True):  # deterministic
        np.testing.assert_array_equal(a.inputs, b.inputs)
    # the teacher demonstrated in the SPEC's 36-in layout with 24-in edges, from starts 24-72 in out (LESSON_FAR) within
    # 0.9 of the door's half-span: its first lesson is what it does there
    env = RobotTaskEnv("DP", layout=Layout.load("default").with_door_width(36.0), edge_jump=24.0,
                       dp_offset=0.9 * 18.0, dp_depth=(24.0, 72.0))
    assert env.layout.doors["A"].width == 36.0 and env.unwrapped.sim.edge_jump == 24.0
    direct = make_taught_lessons("DP", n=1, seed=0, env=env)[0]
    np.testing.assert_array_equal(wide[0].inputs, direct.inputs)
    assert all(w.meta["success"] for w in wide)
    assert any(a.inputs.shape != b.inputs.shape or not np.array_equal(a.inputs, b.inputs)
               for a, b in zip(wide, shipped, strict=True))
    # docking tolerance matters for DK only
    assert all(np.array_equal(a.inputs, b.inputs) for a, b in
               zip(robot.taught_lessons("DP", 2, dock_tolerance=10.0), robot.taught_lessons("DP", 2), strict=True))
    # the door-edge threshold changes DP's inputs only
    edges = robot.taught_lessons("DP", 2, edge_jump=24.0)
    assert not np.array_equal(edges[0].inputs[:, 24:48], shipped[0].inputs[:, 24:48])
    assert all(np.array_equal(a.inputs, b.inputs) for a, b in
               zip(robot.taught_lessons("DK", 2, edge_jump=24.0), robot.taught_lessons("DK", 2), strict=True))
    tiny = RobotParams(trials=4, test_every=2, test_tasks=3, lessons_per_trial=3)
    r = run_robot(replace(tiny, door_width=36.0, dp_heading=45.0, lessons=3), np.random.default_rng(1))
    assert r.curve_x == [0, 2, 4]


def test_lesson_files_are_regenerated_deterministically():
    shipped = load_lessons(robot.lesson_path("DK"), env_id="connrl/Robot-DK-v0")
    fresh = make_taught_lessons("DK", n=2, seed=0)
    for s, f in zip(shipped[:2], fresh, strict=True):
        np.testing.assert_allclose(s.inputs, f.inputs)
        np.testing.assert_array_equal(s.actions, f.actions)
    doc = json.loads(robot.lesson_path("WFL").read_text())
    assert "scripted teacher" in doc["source"] and len(doc["lessons"]) == 5
