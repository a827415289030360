"""The robot's compiled move (``connrl.envs.robot.step``) is ``RobotSim.apply``'s, its room lookup ``Layout.room_at``,
and its hypot CPython's, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from connrl.envs.robot import Layout, RobotSim
from connrl.envs.robot.constants import N_ACTIONS
from connrl.envs.robot.step import _hypot, _move, _room, hypot_matches, room_table


def test_hypot_is_cpythons():
    for a, b in [(3.0, 4.0), (0.0, 0.0), (-5.0, 12.0), (1e-300, 1e-300), (1e300, 1e300), (2.4, 0.0), (0.1, 0.2)]:
        assert _hypot(a, b) == math.hypot(a, b)
    for a, b in np.random.default_rng(7).normal(0, 12, (5000, 2)).tolist():
        assert _hypot(a, b) == math.hypot(a, b)
    assert hypot_matches()


@pytest.mark.parametrize("collision", ["partial", "cancel"])
@pytest.mark.parametrize("step_scale", [1.0, 0.2])
def test_the_compiled_move_is_apply(collision, step_scale):
    sim = RobotSim("default", np.random.default_rng(1), collision=collision, step_scale=step_scale)
    layout, rng, collided = sim.layout, np.random.default_rng(2), 0
    pose, bits = np.empty(3), np.empty(4, dtype=np.uint8)
    for _ in range(1000):
        if rng.random() < 0.01 or not layout.is_free(sim.x, sim.y, 0.0):
            sim.place(*_free_pose(layout, rng))
        a = int(rng.integers(N_ACTIONS)) if rng.random() < 0.4 else int(rng.integers(4, N_ACTIONS))  # moves, mostly
        pose[:] = sim.pose
        u = np.random.default_rng(int(rng.integers(2**31))).random()
        sim.rng = _OneDraw(u)  # apply's one draw, handed to both
        m = sim.apply(a)
        got = _move(pose, a, u, sim.control_noise, sim.step_scale, sim.partial_moves, sim._segs, sim._kinds, bits)
        assert tuple(pose) == sim.pose
        np.testing.assert_array_equal(bits, sim.last_collision)
        assert got[0] == m.collided and got[1] == m.contact_kind
        assert got[2] == m.contact_angle or (math.isnan(got[2]) and math.isnan(m.contact_angle))
        collided += m.collided
    assert collided >= 10  # contacts were exercised


def test_room_is_room_at():
    layout, rng = Layout.load("default"), np.random.default_rng(3)
    names, rooms = list(layout.rooms), room_table(layout)
    w, h = layout.size
    for x, y in np.column_stack([rng.uniform(-10, w + 10, 2000), rng.uniform(-10, h + 10, 2000)]).tolist():
        r = _room(x, y, rooms)
        assert (names[r] if r >= 0 else None) == layout.room_at(x, y)
    for x0, y0, x1, y1 in rooms.tolist():  # the edges: a shared boundary goes to the first room listed
        for x, y in ((x0, y0), (x1, y1), (x0, y1), (x1, y0)):
            r = _room(x, y, rooms)
            assert (names[r] if r >= 0 else None) == layout.room_at(x, y)


def _free_pose(layout, rng):
    w, h = layout.size
    while True:
        x, y = float(rng.uniform(0, w)), float(rng.uniform(0, h))
        if layout.is_free(x, y):
            return x, y, float(rng.uniform(0, 360))


class _OneDraw:
    def __init__(self, u: float):
        self.u = u

    def random(self) -> float:
        return self.u
