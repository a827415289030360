"""Hand-built robot layouts and noise-free simulators for the robot env tests."""

import numpy as np

from connrl.envs.robot import (
    Layout,
    RobotSim,
)


def box_layout(obstacles=(), light=(191.0, 191.0), inner_walls=(), doors=None, size=200):
    """A square room (plus optional inner walls) with the charger tucked in the NE corner."""
    s = size
    return Layout.from_dict({
        "name": "test", "size": [s, s],
        "rooms": {"R": [0, 0, s, s]} if doors is None else {"S": [0, 0, s, 100], "N": [0, 100, s, s]},
        "walls": [[0, 0, s, 0], [s, 0, s, s], [s, s, 0, s], [0, s, 0, 0], *inner_walls],
        "doors": doors or {},
        "obstacles": list(obstacles),
        "charger": {"box": [s - 18, s - 18, s, s], "light": list(light)},
    })


# The hand-drawn readings and moves of these scenes are computed for a body-surface sonar and cancelled moves (the
# world before issue 44); the default world's centre sonar and partial moves have their own scenes in
# test_robot_family.py.
BODY_CANCEL = {"sonar_origin": "body", "collision": "cancel"}


def exact_sim(layout, pose, seed=0):
    sim = RobotSim(layout, np.random.default_rng(seed), sensor_noise=False, control_noise=False, **BODY_CANCEL)
    sim.place(*pose)
    return sim
