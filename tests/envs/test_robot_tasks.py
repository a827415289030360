"""Robot task definitions (5.3, 5.4): sonar encoding, wall-following reinforcement, start regions."""

import math

import numpy as np
import pytest

from connrl.envs.robot import (
    MOVE_BACKWARD,
    MOVE_FORWARD,
    ROBOT_RADIUS,
    TURN_LEFT_15,
    Layout,
    RobotTaskEnv,
    encode_sonar,
    sample_dp_start,
    side_alignment,
    side_clearance,
    wall_following_reward,
)


def test_encode_sonar_5_3_2():
    enc = encode_sonar(np.array([0, 32, 64, 95.5, 127, 200]))
    assert enc.tolist() == [1.0, 0.5, 0.0, -0.125, -0.25, -0.25]


# --- reinforcement functions ------------------------------------------------------------------
def wall_ranges(clearance, alpha_deg, side="left", other=127.0):
    """Readings of a straight wall on ``side`` at body clearance ``clearance`` (perpendicular),
    nose turned ``alpha_deg`` towards it; everything else reads ``other``."""
    r = np.full(24, other)
    d = clearance + ROBOT_RADIUS
    for k in range(24):
        off = 15 * k if side == "left" else -15 * k  # angle of ray k towards the wall side
        psi = 90 - off - alpha_deg  # angle between the ray and the wall normal
        if abs(((off + 180) % 360) - 180) <= 150 and math.cos(math.radians(psi)) > 0.05:
            r[k] = min(other, d / math.cos(math.radians(psi)) - ROBOT_RADIUS)
    return r


@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("alpha", [-20.0, 0.0, 5.0, 12.0])
def test_side_alignment_recovers_the_angle(side, alpha):
    r = wall_ranges(20.0, alpha, side)
    assert side_alignment(r, side) == pytest.approx(alpha, abs=1e-9)


def test_wall_following_reward_cases():
    wf = wall_following_reward
    ok = wall_ranges(20.0, 0.0)
    assert side_clearance(ok, "left") == pytest.approx(20.0)
    assert wf(MOVE_FORWARD, False, ok, "left") == 10
    assert wf(MOVE_FORWARD, False, wall_ranges(20.0, 15.0), "left") == 9
    assert wf(MOVE_FORWARD, False, wall_ranges(20.0, -30.0), "left") == 8
    assert wf(MOVE_FORWARD, True, ok, "left") == -10  # collision first
    assert wf(MOVE_BACKWARD, False, ok, "left") == -3
    assert wf(TURN_LEFT_15, False, ok, "left") == 0  # only forward moves earn 8..10
    assert wf(MOVE_FORWARD, False, wall_ranges(10.0, 0.0), "left") == 0  # too close
    assert wf(MOVE_FORWARD, False, wall_ranges(40.0, 0.0), "left") == 0  # too far
    assert wf(MOVE_FORWARD, False, ok, "right") == 0  # no wall on the right: too far
    both = np.minimum(ok, wall_ranges(10.0, 0.0, "right"))
    assert wf(MOVE_FORWARD, False, both, "left") == 0  # too close on the other side
    assert wf(MOVE_FORWARD, False, wall_ranges(14.0, 0.0), "left") == 10  # 14..32 accepted
    assert wf(MOVE_FORWARD, False, wall_ranges(32.0, 0.0), "left") == 10


# --- start regions --------------------------------------------------------------------------------
def test_start_generators():
    rng = np.random.default_rng(0)
    L = Layout.load("default")
    dk, dp, wf = RobotTaskEnv("DK"), RobotTaskEnv("DP"), RobotTaskEnv("WFL")
    for _ in range(100):
        x, y, h = dk.sample_task(rng)
        assert L.is_free(x, y) and math.hypot(x - 9, y - 9) <= 96 and L.light_visible(x, y) and 0 <= h < 360
        x, y, h = dp.sample_task(rng)
        door = min(abs(x - 114), abs(x - 246))
        assert L.is_free(x, y) and door <= 24 and 24 <= abs(y - 300) <= 72 and 0 <= h < 360  # in front
        x, y, h = wf.sample_task(rng)
        assert L.is_free(x, y) and L.room_at(x, y) in "ABC"


def test_dp_start_region_arguments():
    rng = np.random.default_rng(1)
    L = Layout.load("default")
    pts = [sample_dp_start(rng, L, offset=40.0, depth=(30.0, 36.0)) for _ in range(200)]
    lat = [min(abs(x - 114), abs(x - 246)) for x, _, _ in pts]
    assert max(lat) <= 40 and max(lat) > 24 and all(30 <= abs(y - 300) <= 36 for _, y, _ in pts)
    rooms = {L.room_at(x, y) for x, y, _ in pts}
    assert rooms == {"A", "B", "C"}  # both doors, both sides
    with pytest.raises(ValueError, match="dp_offset"):
        sample_dp_start(rng, L, offset=-1.0)
    with pytest.raises(ValueError, match="dp_depth"):
        sample_dp_start(rng, L, depth=(72.0, 24.0))
    with pytest.raises(ValueError, match="pass_depth"):
        RobotTaskEnv("DP", pass_depth=-1.0)
    with pytest.raises(ValueError, match="dp_heading"):
        RobotTaskEnv("DP", dp_heading=181.0)


def test_dp_start_heading_faces_the_door():
    rng = np.random.default_rng(2)
    env = RobotTaskEnv("DP", dp_heading=45.0)
    for _ in range(200):
        x, y, h = env.sample_task(rng)
        through = 90.0 if y < 300 else -90.0  # north from A/B, south from C
        assert abs((h - through + 180.0) % 360.0 - 180.0) <= 45.0 + 1e-9
        assert 0.0 <= h < 360.0
    # any heading (the default) keeps the draws of the generator before dp_heading existed (commit c29cf40), in the
    # start region of then (within the door's span, 24-72 in out)
    spec = Layout.load("default").with_door_width(36.0)
    env = RobotTaskEnv("DP", layout=spec, dp_offset=18.0, dp_depth=(24.0, 72.0))
    assert env.sample_task(np.random.default_rng(3)) == pytest.approx(
        (256.8458807474303, 351.94377773108965, 33.88631120654371), abs=1e-12)
