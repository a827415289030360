"""HEROINE layouts: the reconstructed default and changed layouts, errors, round trip, door widths."""

import pytest

from connrl.envs.robot import (
    Layout,
)
from tests.envs.robot_scenes import box_layout


def test_default_layout_matches_spec():
    L = Layout.load("default")
    assert L.size == (360.0, 420.0)
    assert L.rooms == {"A": (0, 0, 180, 300), "B": (180, 0, 360, 300), "C": (0, 300, 360, 420)}
    # 49-in doors about the SPEC's centres x = 114 and 246 (issue 44's pick, docs/RECONSTRUCTION.md)
    assert L.doors["A"].segment == (89.5, 300, 138.5, 300) and L.doors["B"].segment == (221.5, 300, 270.5, 300)
    assert all(d.width == 49 for d in L.doors.values())
    assert set(L.obstacles) == {(72, 150, 120, 174), (132, 36, 168, 72), (252, 168, 300, 192)}
    assert L.charger == (0, 0, 18, 18) and L.light == (9, 9)
    for name, loc in L.locations.items():
        assert L.is_free(loc[0], loc[1]), name
    assert L.room_at(*L.locations["L1"][:2]) == "B" and L.room_at(*L.locations["L2"][:2]) == "A"
    assert L.light_visible(*L.locations["L2"][:2])  # Fig. 5.3(d): light seen from L2


def test_changed_layout_differs_as_in_8_4():
    d, c = Layout.load("default"), Layout.load("changed")
    assert c.charger != d.charger and c.charger[0] == 0  # moved along A's west wall
    assert all(c.doors[k].segment != d.doors[k].segment for k in "AB")
    in_a = [o for o in c.obstacles if o[2] <= 180]
    in_b = [o for o in c.obstacles if o[0] >= 180]
    assert len(in_a) == 3 and len(in_b) == 2
    assert not set(in_a) & set(d.obstacles)  # both A obstacles moved
    for name, loc in c.locations.items():
        assert c.is_free(loc[0], loc[1]), name
    assert set(d.obstacles) - set(c.obstacles) == set(d.obstacles[:2])  # B's obstacle stays, A's two moved
    assert [c.doors[k].center[0] - d.doors[k].center[0] for k in "AB"] == [-36.0, 36.0]  # both doors shifted 36 in
    assert [c.doors[k].width for k in "AB"] == [d.doors[k].width for k in "AB"]
    for k, g in (("A", "4"), ("B", "5")):  # the hidden-state subgoals stay in front of the doors, as in default
        assert c.subgoals[g][0] == c.doors[k].center[0] and c.room_at(*c.subgoals[g]) == "C"


def test_changed_layout_is_solvable_from_every_room():
    # the scripted recharging teacher (true pose, the layout's own route) docks from every room of the changed layout
    import numpy as np

    from connrl.envs.robot.recharge import RechargeEnv, sample_in_room
    from connrl.envs.robot.teachers import teach_chg
    env, rng = RechargeEnv(layout="changed"), np.random.default_rng(0)
    for room in "ABC":
        for k in range(2):
            assert teach_chg(env, sample_in_room(rng, env.layout, room), seed=k)[-1][4], room


def test_layout_errors_are_clear():
    with pytest.raises(ValueError, match="unknown layout 'nope'"):
        Layout.load("nope")
    with pytest.raises(ValueError, match="missing keys"):
        Layout.from_dict({"name": "x"})
    with pytest.raises(ValueError, match="obstacle 0"):
        box_layout(obstacles=[[10, 10, 5, 20]])


def test_layout_round_trips_through_dict():
    L = Layout.load("default")
    assert Layout.from_dict(L.to_dict()) == L


def test_with_door_width_widens_each_door_about_its_centre():
    d = Layout.load("default").with_door_width(36.0)  # the SPEC reconstruction's doors
    assert {k: v.segment for k, v in d.doors.items()} == {"A": (96.0, 300.0, 132.0, 300.0),
                                                          "B": (228.0, 300.0, 264.0, 300.0)}
    w = d.with_door_width(48.0)
    assert {k: v.segment for k, v in w.doors.items()} == {"A": (90.0, 300.0, 138.0, 300.0),
                                                          "B": (222.0, 300.0, 270.0, 300.0)}
    walls_300 = sorted(x for x in w.walls if x[1] == x[3] == 300.0)
    assert walls_300 == [(0.0, 300.0, 90.0, 300.0), (138.0, 300.0, 222.0, 300.0), (270.0, 300.0, 360.0, 300.0)]
    assert [x for x in w.walls if x not in walls_300] == [x for x in d.walls if not x[1] == x[3] == 300.0]
    assert d.with_door_width(36.0).walls == d.walls  # the reconstruction's own width changes nothing
    # a centre just outside the old jambs' reach is blocked at 36 in and free at 48 in
    assert not d.is_free(103.0, 300.0) and w.is_free(103.0, 300.0)
    with pytest.raises(ValueError, match="door width"):
        d.with_door_width(20.0)
    with pytest.raises(ValueError, match="swallow"):
        d.with_door_width(200.0)
    returned = Layout.from_dict({**d.to_dict(), "walls": [*map(list, d.walls), [132, 300, 132, 290]]})
    with pytest.raises(ValueError, match="meets a jamb at an angle"):
        returned.with_door_width(48.0)
