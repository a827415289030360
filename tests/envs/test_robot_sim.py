"""HEROINE simulator: sensors on hand-built scenes, collisions, control error, determinism."""

import math

import numpy as np
import pytest

from connrl.envs.robot import (
    BACK,
    FRONT,
    LEFT,
    MOVE_BACKWARD,
    MOVE_FORWARD,
    RIGHT,
    SEG_CHARGER,
    TURN_LEFT_15,
    TURN_LEFT_60,
    TURN_RIGHT_15,
    Layout,
    RobotSim,
    collision_side,
)
from tests.envs.robot_scenes import BODY_CANCEL, box_layout, exact_sim


def test_place_rejects_overlap():
    sim = RobotSim(box_layout(), np.random.default_rng(0))
    with pytest.raises(ValueError, match="overlaps"):
        sim.place(5, 100, 0)
    with pytest.raises(ValueError, match="outside"):
        sim.place(-50, 100, 0)


# --- sonar ----------------------------------------------------------------------------------------
def test_sonar_exact_without_noise():
    sim = exact_sim(box_layout(), (100, 150, 90))  # facing north
    r = sim.sense().sonar
    assert r[0] == 200 - 150 - 12  # ahead: north wall, body distance
    assert r[6] == 100 - 12 and r[18] == 100 - 12  # left (west) and right (east)
    assert r[12] == 127  # behind: 138 in, clipped
    assert r[3] == round(50 * math.sqrt(2) - 12)  # 135 deg: north wall at 45 deg incidence


def test_sonar_noise_bounds_and_dropouts():
    # 100x100 room: every true reading is under 64 in, so a 127 can only be a dropout.
    L = Layout.from_dict({"name": "small", "size": [100, 100], "rooms": {"R": [0, 0, 100, 100]},
                          "walls": [[0, 0, 100, 0], [100, 0, 100, 100], [100, 100, 0, 100], [0, 100, 0, 0]],
                          "doors": {}, "obstacles": [], "charger": {"box": [82, 82, 100, 100]}})
    sim = RobotSim(L, np.random.default_rng(5), control_noise=False, **BODY_CANCEL)
    sim.place(50, 40, 90)
    true = sim.true_ranges()
    n, drop_scans = 4000, 0
    for _ in range(n):
        s = sim.sense().sonar
        drops = s == 127
        assert drops.sum() <= 1
        drop_scans += drops.any()
        ok = ~drops
        assert np.all(s[ok] >= np.floor(0.9 * true[ok] + 0.5) - 1e-9)
        assert np.all(s[ok] <= np.floor(1.1 * true[ok] + 0.5) + 1e-9)
    assert abs(drop_scans / n - 0.25) < 0.03  # one faulty reading in every 4 scans on average


# --- door edges -----------------------------------------------------------------------------------
def test_door_edge_bits_on_hand_built_doorway():
    # Wall y=100 with a 36-in door at x 80..116; robot 24 in north of it facing south (heading 270).
    L = box_layout(inner_walls=[[0, 100, 80, 100], [116, 100, 200, 100]],
                   doors={"D": {"segment": [80, 100, 116, 100], "rooms": ["S", "N"]}})
    rd = exact_sim(L, (98, 124, 270)).sense()
    # Hand-computed readings: ray 2 (300 deg) passes the door (offset 24 tan30 = 13.9 < 18) -> 127;
    # ray 3 (315 deg) hits the wall beside the door at 24*sqrt2 - 12 = 22; ray 4: 24/cos60 - 12 = 36;
    # ray 5: 24/cos75 - 12 = 81. Mirror image on rays 22, 21, 20.
    assert rd.sonar[[2, 3, 4, 5]].tolist() == [127, 22, 36, 81]
    assert rd.sonar[[22, 21, 20, 19]].tolist() == [127, 22, 36, 81]
    # Door jambs: 127 -> 22 marks rays 3 and 21 (the nearer reading). The wall seen at a grazing
    # angle (36 -> 81) also jumps >= 24 and marks 4 and 20: "door edge readings are unreliable" (5.2.1).
    assert np.flatnonzero(rd.door_edge).tolist() == [3, 4, 20, 21]
    # The threshold (R, 37 in by default) decides which jumps count: above the grazing 45-in jump only the jambs'
    # 105-in jumps are left; at 106 in none.
    for jump, bits in ((24.0, [3, 4, 20, 21]), (46.0, [3, 21]), (106.0, [])):
        sim = RobotSim(L, np.random.default_rng(0), sensor_noise=False, control_noise=False, edge_jump=jump,
                       **BODY_CANCEL)
        sim.place(98, 124, 270)
        assert np.flatnonzero(sim.sense().door_edge).tolist() == bits, jump
    with pytest.raises(ValueError, match="edge_jump"):
        RobotSim(L, edge_jump=0.0)


def test_dropout_fakes_door_edges():
    # Facing a wall 12 in away, rays 22..2 read 12..16 in: no edges among them, unless a dropout (127)
    # hits one of them, which then marks both its neighbours (5.2.1: faulty readings look like doors).
    sim = RobotSim(box_layout(), np.random.default_rng(2), control_noise=False, **BODY_CANCEL)
    sim.place(100, 176, 90)
    hits = 0
    for _ in range(400):
        rd = sim.sense()
        if rd.sonar[0] == 127:
            hits += 1
            assert rd.door_edge[1] and rd.door_edge[23]
        elif not (rd.sonar[[22, 23, 1, 2]] == 127).any():
            assert not rd.door_edge[[23, 0, 1]].any()
    assert hits > 0


# --- light ----------------------------------------------------------------------------------------
def test_light_bit_clear_line_of_sight():
    L = box_layout()  # light at (191, 191)
    rd = exact_sim(L, (120, 120, 45)).sense()  # facing the light, 100 in away
    assert np.flatnonzero(rd.light).tolist() == [0]
    rd = exact_sim(L, (120, 120, 45 + 90 + 5)).sense()  # light 95 deg to the right -> ray 18 (-90)
    assert np.flatnonzero(rd.light).tolist() == [18]


def test_light_bit_blocked_by_obstacle_and_range():
    blocked = box_layout(obstacles=[[140, 140, 160, 160]])
    assert not exact_sim(blocked, (120, 120, 45)).sense().light.any()
    far = box_layout(size=300, light=(291, 291))
    assert not exact_sim(far, (180, 180, 45)).sense().light.any()  # 157 in > 120 in


def test_charger_does_not_block_its_own_light():
    L = Layout.load("default")
    rd = exact_sim(L, (30, 30, 225)).sense()  # next to the charger, facing it
    assert rd.light[0] == 1


# --- motion and collisions ------------------------------------------------------------------------
def test_collision_cancels_move_and_sets_front_bit():
    sim = exact_sim(box_layout(), (100, 20, 270))  # 8 in of clearance to the south wall
    m = sim.apply(MOVE_FORWARD)
    assert m.collided and m.side == FRONT and sim.pose == (100, 20, 270)
    assert sim.sense().collision.tolist() == [1, 0, 0, 0]
    m = sim.apply(TURN_LEFT_60)  # turning never collides and clears the bits
    assert not m.collided and sim.sense().collision.tolist() == [0, 0, 0, 0]


def test_backward_collision_sets_back_bit():
    sim = exact_sim(box_layout(), (100, 20, 90))
    m = sim.apply(MOVE_BACKWARD)
    assert m.collided and m.side == BACK and (sim.x, sim.y) == (100, 20)
    assert sim.sense().collision.tolist() == [0, 1, 0, 0]


def test_grazing_corner_sets_side_bit():
    # Moving east at y=100 past an obstacle corner at (106, 111), 11 in off the path: first contact at
    # centre x = 106 - sqrt(144 - 121), with the contact point atan2(11, sqrt(23)) = 66 deg to the left.
    L = box_layout(obstacles=[[106, 111, 130, 140]])
    m = exact_sim(L, (95, 100, 0)).apply(MOVE_FORWARD)
    assert m.collided and m.side == LEFT
    assert m.contact_angle == pytest.approx(math.degrees(math.atan2(11, math.sqrt(23))))
    assert not exact_sim(L, (80, 100, 0)).apply(MOVE_FORWARD).collided  # ends at x=92, 17.8 in away
    right = box_layout(obstacles=[[106, 60, 130, 89]])
    assert exact_sim(right, (95, 100, 0)).apply(MOVE_FORWARD).side == RIGHT


def test_swept_disc_catches_contact_between_start_and_end():
    # A thin post whose corner comes within 11.9 in of the path only mid-move: both end poses are clear.
    L = box_layout(obstacles=[[105, 111.9, 106, 140]])
    sim = exact_sim(L, (98, 100, 0))
    assert L.clearance(110, 100) > 12 and L.clearance(98, 100) > 12
    m = sim.apply(MOVE_FORWARD)
    assert m.collided and m.side == LEFT and (sim.x, sim.y) == (98, 100)


def test_collision_side_sectors():
    assert [collision_side(a) for a in (0, 45, 46, 134, 135, -46, -134, 180)] == [
        FRONT, FRONT, LEFT, LEFT, BACK, RIGHT, RIGHT, BACK]


def test_move_hits_charger_reports_kind():
    sim = exact_sim(Layout.load("default"), (30, 30, 225))
    m = sim.apply(MOVE_FORWARD)
    assert m.collided and m.contact_kind == SEG_CHARGER and abs(m.contact_angle) < 1e-6


def test_control_error_bounds():
    sim = RobotSim(box_layout(size=2000), np.random.default_rng(1), sensor_noise=False)
    turns, moves = [], []
    for _ in range(500):
        sim.place(1000, 1000, 0)
        sim.apply(TURN_LEFT_15)
        turns.append(sim.heading)
        sim.place(1000, 1000, 0)
        sim.apply(MOVE_FORWARD)
        moves.append(sim.x - 1000)
    turns, moves = np.array(turns), np.array(moves)
    assert turns.min() >= 15 * 0.92 and turns.max() <= 15 * 1.08
    assert moves.min() >= 12 * 0.92 and moves.max() <= 12 * 1.08
    assert turns.min() < 15 * 0.93 and turns.max() > 15 * 1.07  # the full +-8% is used
    sim.place(1000, 1000, 10)
    sim.control_noise = False
    sim.apply(TURN_RIGHT_15)
    assert sim.heading == 355.0


def test_same_seed_same_trajectory_and_readings():
    def run(seed):
        sim = RobotSim("default", np.random.default_rng(seed))
        sim.place(300, 60, 90)
        out = []
        for a in np.random.default_rng(99).integers(0, 6, 200):
            sim.apply(int(a))
            rd = sim.sense()
            out.append(np.concatenate([sim.pose, rd.sonar, rd.light, rd.door_edge, rd.collision]))
        return np.array(out)

    assert np.array_equal(run(3), run(3))
    assert not np.array_equal(run(3), run(4))


def test_invalid_action_is_rejected():
    sim = exact_sim(box_layout(), (100, 100, 0))
    with pytest.raises(ValueError, match="action must be an integer in 0..5"):
        sim.apply(6)
