"""Constants of the HEROINE robot, its actions and its sensors (5.2.1; R: docs/RECONSTRUCTION.md, "HEROINE robot
world")."""

from __future__ import annotations

# The sensor constants the compiled geometry reads are defined beside its kernels (Numba freezes a global into a
# cached kernel and notices an edit of the kernel's own file only; issue 25), and re-exported here.
from connrl.envs.robot.geometry import (  # noqa: F401
    DROPOUT_PROB,
    LIGHT_HALF_ANGLE,
    LIGHT_RANGE,
    RAY_STEP_DEG,
    SEG_CHARGER,
    SEG_OBSTACLE,
    SEG_WALL,
    SONAR_ERROR,
    SONAR_MAX,
)

# ---------------------------------------------------------------------------------------------------
# Constants of the robot and its sensors (5.2.1; R: docs/RECONSTRUCTION.md, "HEROINE robot world")
ROBOT_RADIUS = 12.0  # inches (Fig. 5.3 caption)
N_RAYS = 24  # sonar / light readings per rotation, 15 deg apart (5.2.1)
CONTROL_ERROR = 0.08  # "about 8% control error" (5.2.1; R: uniform on length and angle)
# The default world: issue 44's pick among the readings of the text that meet the no-teaching DP target
# (docs/RECONSTRUCTION.md, "The robot world as a family"; all R). The layout file holds its 49-in doors.
DOOR_EDGE_JUMP = 37  # neighbouring readings differing by this much mark a potential door edge
EDGE_MARK = "nearer"  # ... on the nearer of the two readings
SONAR_ORIGIN = "centre"  # sonar distances from the robot's centre (not its body surface)
COLLISION = "partial"  # a move that would touch a surface stops at the contact
DP_FAR = 52.0  # DP starts lie 24..DP_FAR in from the door's wall ...
DP_LATERAL = 0.9  # ... within +-DP_LATERAL x half the door's width of its centre
PASS_DEPTH = 0.0  # DP succeeds once the centre is in another room

# Actions, in the order of 5.2.1 ("turn +-15, turn +-60, move +-12").
TURN_LEFT_15, TURN_RIGHT_15, TURN_LEFT_60, TURN_RIGHT_60, MOVE_FORWARD, MOVE_BACKWARD = range(6)
N_ACTIONS = 6
ACTION_NAMES = ("turn +15", "turn -15", "turn +60", "turn -60", "move +12", "move -12")
ACTION_TURN_DEG = (15.0, -15.0, 60.0, -60.0, 0.0, 0.0)
ACTION_MOVE_IN = (0.0, 0.0, 0.0, 0.0, 12.0, -12.0)

# Keyboard teaching tool: six keys -> actions (arrow-free so it works in any terminal).
KEYMAP = {
    "a": TURN_LEFT_15,
    "d": TURN_RIGHT_15,
    "q": TURN_LEFT_60,
    "e": TURN_RIGHT_60,
    "w": MOVE_FORWARD,
    "s": MOVE_BACKWARD,
}

# Collision bit order.
FRONT, BACK, LEFT, RIGHT = range(4)
COLLISION_SIDES = ("front", "back", "left", "right")


_RNG_PER_SCAN = 26  # 24 sonar noise factors + dropout coin + dropout index


