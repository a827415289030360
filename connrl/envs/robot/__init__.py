"""HEROINE, the mobile-robot simulator of thesis Ch. 5 (5.2), used again in Ch. 6 and Ch. 8.

Description:
    A disc robot (radius 12 in) in a three-room office (Fig. 5.3): rooms A (south-west) and B
    (south-east) open through two 49-in doorways onto room C (a strip along the north wall). A battery
    charger with a light on top sits in A's south-west corner. This module holds the world only:
    the :class:`Layout` (plain JSON data under ``connrl/data/layouts/``), the robot's motion with
    control error and collision handling, its sensors (sonar, light, door-edge, collision, compass,
    room), and rendering. The learning tasks built on it are :mod:`connrl.envs.robot.tasks` (encoding,
    rewards, starts), :mod:`connrl.envs.robot.env` (``RobotTaskEnv``) and :mod:`connrl.envs.robot.teachers`.

    Frame: x east, y north, inches; headings in degrees counter-clockwise from east.

Action Space:
    Six primitive actions (5.2.1), in the order the thesis lists them:
    0 turn +15 deg (left), 1 turn -15 deg (right), 2 turn +60 deg (left), 3 turn -60 deg (right),
    4 move +12 in (forward), 5 move -12 in (backward).

Sensors (``RobotSim.sense`` -> :class:`Reading`):
    - sonar: 24 readings, ray ``k`` points at ``heading + 15k`` deg (robot-centred: ray 0 ahead,
      ray 6 left, ray 12 behind, ray 18 right). A reading is the distance from the robot's centre
      (``sonar_origin="centre"``; ``"body"``: from the disc edge) to the first surface along the ray, times
      U(0.9, 1.1), rounded to 1 in, clipped to 0..127. With probability 1/4 per scan one random reading is
      replaced by 127 (5.2.1). ``Reading.body_sonar`` gives body distances whatever the origin.
    - light: 24 bits; bit ``k`` is on when the light lies within +-7.5 deg of ray ``k``, within 120 in
      of the robot's centre, and no wall or obstacle blocks the line of sight (the charger itself
      does not: the light sits on top of it).
    - door edge: 24 bits computed from the (noisy) sonar scan; when two neighbouring readings differ
      by ``edge_jump`` (37 in) or more, the bit of the *nearer* reading is set (that is where the edge is;
      ``edge_mark="both"`` sets both).
    - collision: 4 bits in the order (front, back, left, right); set after a move that touched a surface,
      on the side where the body touched: front |angle| <= 45 deg, left 45..135,
      back >= 135, right -135..-45 (angle of the contact point relative to the heading).
    - compass (heading, degrees) and the current room (the room rectangle holding the centre).

Dynamics:
    A turn changes the heading by the nominal angle times U(0.92, 1.08); a move translates the
    centre by the nominal length times U(0.92, 1.08) along the heading (8% control error, 5.2.1).
    Turning never collides (a disc turning in place sweeps nothing). A move whose swept disc would
    touch any wall, obstacle or the charger box stops at the contact (``collision="partial"``; ``"cancel"``:
    the robot stays where it was), and the collision bit of the side of first contact is set.

Randomness:
    All noise comes from the ``numpy.random.Generator`` handed to :class:`RobotSim`. Every action
    draws a fixed number of variates (1 for control, 26 for a scan) whether or not noise is enabled,
    so switching noise off does not shift the random stream of anything else.

Differences from the thesis:
    - The geometry, the noise model and the door-edge/light rules are reconstructions (R; see
      docs/RECONSTRUCTION.md, "HEROINE robot world"): the thesis's Fig. 5.3 is lost. Walls have zero thickness.
    - The thesis does not say where sonar distances are measured from, what a colliding move does, how wide
      the doors are or what jump marks a door edge. The defaults (centre sonar, moves stopped at the contact,
      49-in doors, 37-in edges) are issue 44's pick among the readings that meet the thesis's no-teaching door
      passing curve (docs/RECONSTRUCTION.md, "The robot world as a family"); the world before it (body sonar,
      cancelled moves, 48-in doors, 44-in edges) is a parameter setting.
    - Light bits are noise-free; the thesis's ~10% sensing error is applied to the sonar only.
    - The changed layout of 8.4 (``changed.json``) is our reconstruction of the lost Fig. 8.2.
"""

from connrl.envs.robot.constants import (
    ACTION_MOVE_IN,
    ACTION_NAMES,
    ACTION_TURN_DEG,
    BACK,
    COLLISION_SIDES,
    CONTROL_ERROR,
    DOOR_EDGE_JUMP,
    DROPOUT_PROB,
    FRONT,
    KEYMAP,
    LEFT,
    LIGHT_HALF_ANGLE,
    LIGHT_RANGE,
    MOVE_BACKWARD,
    MOVE_FORWARD,
    N_ACTIONS,
    N_RAYS,
    RAY_STEP_DEG,
    RIGHT,
    ROBOT_RADIUS,
    SEG_CHARGER,
    SEG_OBSTACLE,
    SEG_WALL,
    SONAR_ERROR,
    SONAR_MAX,
    TURN_LEFT_15,
    TURN_LEFT_60,
    TURN_RIGHT_15,
    TURN_RIGHT_60,
)
from connrl.envs.robot.env import RobotTaskEnv
from connrl.envs.robot.layout import LAYOUT_DIR, Door, Layout
from connrl.envs.robot.render import (
    HumanViewer,
    draw_layout,
    draw_robot,
    render_figure_5_3,
    render_frame,
    render_paths,
    save_png,
)
from connrl.envs.robot.sim import Motion, Reading, RobotSim, collision_side, wrap_deg
from connrl.envs.robot.tasks import (
    OBS_SIZE,
    R_BACKWARD,
    R_COLLISION,
    R_SUCCESS,
    TASKS,
    WF_PARALLEL_DEG,
    WF_REWARDS,
    encode_sonar,
    sample_anywhere,
    sample_dk_start,
    sample_dp_start,
    side_alignment,
    side_clearance,
    wall_following_reward,
)
from connrl.envs.robot.teachers import teach, teach_dk, teach_dp, teach_wf, wall_following_action

__all__ = ["ACTION_MOVE_IN", "ACTION_NAMES", "ACTION_TURN_DEG", "BACK", "COLLISION_SIDES", "CONTROL_ERROR",
           "DOOR_EDGE_JUMP", "DROPOUT_PROB", "Door", "FRONT", "HumanViewer", "KEYMAP", "LAYOUT_DIR", "LEFT",
           "LIGHT_HALF_ANGLE", "LIGHT_RANGE", "Layout", "MOVE_BACKWARD", "MOVE_FORWARD", "Motion", "N_ACTIONS",
           "N_RAYS", "OBS_SIZE", "RAY_STEP_DEG", "RIGHT", "ROBOT_RADIUS", "R_BACKWARD", "R_COLLISION", "R_SUCCESS",
           "Reading", "RobotSim", "RobotTaskEnv", "SEG_CHARGER", "SEG_OBSTACLE", "SEG_WALL", "SONAR_ERROR",
           "SONAR_MAX", "TASKS", "TURN_LEFT_15", "TURN_LEFT_60", "TURN_RIGHT_15", "TURN_RIGHT_60", "WF_PARALLEL_DEG",
           "WF_REWARDS", "collision_side", "draw_layout", "draw_robot", "encode_sonar", "render_figure_5_3",
           "render_frame", "render_paths", "sample_anywhere", "sample_dk_start", "sample_dp_start", "save_png",
           "side_alignment", "side_clearance", "teach", "teach_dk", "teach_dp", "teach_wf", "wall_following_action",
           "wall_following_reward", "wrap_deg"]
