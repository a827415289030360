"""Issue 44's open details of the robot world, on hand-built scenes: sonar origin, collision model, door-edge
marking, DP start spread and success depth (the search itself: tests/experiments/test_world_family.py)."""


import numpy as np
import pytest

from connrl.envs.robot import MOVE_FORWARD, RobotSim, RobotTaskEnv
from connrl.experiments.robot import RobotParams
from connrl.tasks import robot
from tests.envs.robot_scenes import BODY_CANCEL, box_layout

DOORWAY = {"inner_walls": [[0, 100, 80, 100], [116, 100, 200, 100]],
           "doors": {"D": {"segment": [80, 100, 116, 100], "rooms": ["S", "N"]}}}


def _sim(layout, pose, **kw):
    sim = RobotSim(layout, np.random.default_rng(0), sensor_noise=False, control_noise=False, **(BODY_CANCEL | kw))
    sim.place(*pose)
    return sim


def test_sonar_origin_centre_reads_the_radius_more_and_leaves_the_true_ranges():
    body = _sim(box_layout(), (100, 150, 90), sonar_origin="body").sense()
    centre = _sim(box_layout(), (100, 150, 90), sonar_origin="centre").sense()
    assert body.sonar[0] == 38 and centre.sonar[0] == 50  # north wall 50 in from the centre
    assert centre.sonar[6] == 100 and centre.sonar[12] == 127  # west wall 100 in; behind 150 in, clipped
    assert np.array_equal(body.ranges, centre.ranges)  # rewards read body distances in both


def test_partial_move_stops_at_the_contact_and_cancel_stays_put():
    # 5 in between the body and the north wall: a 12-in forward move touches after 5 in.
    for collision, y_after in (("cancel", 183.0), ("partial", 188.0)):
        sim = _sim(box_layout(), (100, 183, 90), collision=collision)
        motion = sim.apply(MOVE_FORWARD)
        assert motion.collided and sim.last_collision[0] == 1
        assert sim.x == pytest.approx(100) and sim.y == pytest.approx(y_after, abs=0.01)
        assert sim.y <= 188.0  # never into the wall
    free = _sim(box_layout(), (100, 100, 90), collision="partial")
    assert not free.apply(MOVE_FORWARD).collided and free.y == pytest.approx(112)


def test_edge_mark_both_marks_both_readings_of_each_jump():
    # The hand-computed doorway of test_robot_sim: jumps 127 -> 22 between rays 2|3 and 22|21 (the jambs).
    L = box_layout(**DOORWAY)
    nearer = _sim(L, (98, 124, 270), edge_jump=46.0).sense().door_edge
    both = _sim(L, (98, 124, 270), edge_jump=46.0, edge_mark="both").sense().door_edge
    assert np.flatnonzero(nearer).tolist() == [3, 21]
    assert np.flatnonzero(both).tolist() == [2, 3, 21, 22]


def test_unknown_detail_values_are_refused():
    for kw in ({"sonar_origin": "nose"}, {"collision": "bounce"}, {"edge_mark": "far"}):
        with pytest.raises(ValueError, match="must be one of"):
            RobotSim(box_layout(), **kw)
    with pytest.raises(ValueError, match="dp_lateral must be in"):
        RobotParams(dp_lateral=5.0)
    with pytest.raises(ValueError, match="pass_depth must be in"):
        RobotParams(pass_depth=-1.0)
    with pytest.raises(ValueError, match="apply to task DP only"):
        RobotParams(task="DK", edge_mark="both").check_combination()
    with pytest.raises(TypeError, match="unknown world detail"):
        robot.taught_lessons("DP", 1, door_span=40)


def test_dp_lateral_sets_the_start_spread_along_the_wall():
    p = RobotParams(dp_lateral=2.0, door_width=36.0)
    env = robot.make_env(p)
    rng = np.random.default_rng(0)
    doors = list(env.layout.doors.values())
    offsets = [min(abs(s[0] - d.center[0]) for d in doors) for s in (env.sample_task(rng) for _ in range(400))]
    assert max(offsets) <= 36.0 + 1e-9 and max(offsets) > 30.0  # +-2 x 18 in about the door's centre
    narrow = robot.make_env(RobotParams(door_width=36.0))
    assert max(min(abs(s[0] - d.center[0]) for d in doors) for s in
               (narrow.sample_task(rng) for _ in range(400))) <= 18.0 + 1e-9


def test_pass_depth_reaches_the_environment():
    assert robot.make_env(RobotParams(pass_depth=12.0)).pass_depth == 12.0
    env = RobotTaskEnv("DP", sonar_origin="centre", collision="partial", edge_mark="both")
    assert env.sim.sonar_radius == 0.0 and env.sim.partial_moves and env.sim.edge_both


def test_changed_world_details_demonstrate_afresh_and_others_read_the_file():
    shipped = robot.taught_lessons("DP", 2)
    changed = robot.taught_lessons("DP", 2, sonar_origin="body")
    assert not np.array_equal(shipped[0].inputs, changed[0].inputs)
    # DK does not see door edges: its lessons stay the file's when only the DP marking changes
    assert all(np.array_equal(a.inputs, b.inputs) for a, b in
               zip(robot.taught_lessons("DK", 2, edge_mark="both"), robot.taught_lessons("DK", 2), strict=True))
