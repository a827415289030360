"""Ch. 5's greedy test plays compiled whole (issue 45).

Every Ch. 5 run tests its learner greedily on fixed tasks before the first trial and every few trials (5.4). Here
a test play -- the learner's values and greedy choice, the simulator's move and scan, the task's reinforcement and its
observation -- runs as one Numba loop with the same arithmetic and the same draws from the world's generator, step for
step, as ``run_trial(env, agent, learning=False, max_steps=...)``; tests/tasks/test_robot_play.py holds every play,
and the world and learner it leaves, to ``run_trial``'s.

Only the plain case is compiled: a ``RobotTaskEnv`` without rendering and a QCON (or Ch. 5's QCON-T) over an
``OAON`` with no planner; anything else plays through ``run_trial``, as it does where the ported ``math.hypot`` is not
the interpreter's (``connrl.envs.robot.step``). Not cached, as ``connrl.tasks.recharge_play``.
"""

from __future__ import annotations

import numba
import numpy as np

from connrl.agents.qcon import QCON
from connrl.agents.teaching import TeachingQCON
from connrl.core.exploration import boltzmann_probabilities
from connrl.core.rollout import TrialStats
from connrl.envs.robot.constants import (
    MOVE_BACKWARD,
    MOVE_FORWARD,
    N_ACTIONS,
    N_RAYS,
    ROBOT_RADIUS,
)
from connrl.envs.robot.env import RobotTaskEnv
from connrl.envs.robot.sim import Reading, RobotSim
from connrl.envs.robot.step import _act_and_sense, _docked, _hypot, _room, hypot_matches, leave, room_table
from connrl.envs.robot.tasks import (
    CLEARANCE_MAX,
    CLEARANCE_MIN,
    OBS_SIZE,
    R_BACKWARD,
    R_COLLISION,
    R_SUCCESS,
    TASKS,
    WF_PARALLEL_DEG,
    WF_REWARDS,
    _fill_obs,
    _side_features,
)
from connrl.nets import OAON
from connrl.nets.kernels import _values_any

_WF_REWARDS = np.array(WF_REWARDS)
_WF_PARALLEL = np.array(WF_PARALLEL_DEG)


@numba.njit(cache=False)
def _as_input(obs, x):
    """``np.asarray(obs, dtype=np.float64)`` into ``x``, which it returns."""
    for k in range(obs.size):
        x[k] = obs[k]
    return x


@numba.njit(cache=False)
def _greedy_choice(q):
    """QCON's action at T = 0 (``boltzmann_select``): the first best; 0 when a value is NaN (np.argmax of NaNs)."""
    a, nan = 0, False
    for k in range(q.size):
        nan = nan or np.isnan(q[k])
        if q[k] > q[a]:
            a = k
    return 0 if nan else a


@numba.njit(cache=False)
def _passed_door(x, y, room, start_room, doors, pass_depth):
    """``RobotTaskEnv._passed_door``: into another room, and (``pass_depth`` > 0) that far from every doorway."""
    if room < 0 or room == start_room:
        return False
    if pass_depth <= 0.0:
        return True
    for d in range(doors.shape[0]):
        x0, y0, x1, y1 = doors[d, 0], doors[d, 1], doors[d, 2], doors[d, 3]
        ex, ey = x1 - x0, y1 - y0
        s = ((x - x0) * ex + (y - y0) * ey) / (ex * ex + ey * ey)
        s = s if s > 0.0 else 0.0  # Python's max(0.0, s), then min(1.0, s)
        s = s if s < 1.0 else 1.0
        if _hypot(x0 + s * ex - x, y0 + s * ey - y) < pass_depth:
            return False
    return True


@numba.njit(cache=False)
def _wf_reward(task, a, collided, ranges, feat_true):
    """``RobotTaskEnv._wf_reward``: wall following's reinforcement on the true ranges (5.3.1)."""
    if collided:
        return R_COLLISION
    if a == MOVE_BACKWARD:
        return R_BACKWARD
    _side_features(ranges, ROBOT_RADIUS, feat_true)
    j = 0 if task == 2 else 1
    near = feat_true[3] if feat_true[3] < feat_true[2] else feat_true[2]
    if near < CLEARANCE_MIN or feat_true[2 + j] > CLEARANCE_MAX or a != MOVE_FORWARD:
        return 0.0
    al = abs(feat_true[j])
    return _WF_REWARDS[0] if al <= _WF_PARALLEL[0] else _WF_REWARDS[1] if al <= _WF_PARALLEL[1] else _WF_REWARDS[2]


def robot_world(env: RobotTaskEnv) -> tuple:
    """What ``_robot_step`` reads of a world: the task, the simulator's surfaces and settings, the rooms, the start
    room and doors (DP), the observation's settings and the time limit."""
    sim, layout = env.sim, env.layout
    start_room = list(layout.rooms).index(env._start_room) if env._start_room is not None else -1
    doors = np.array([d.segment for d in layout.doors.values()], dtype=np.float64).reshape(-1, 4)
    return (TASKS.index(env.task), sim._segs, sim._kinds, np.array(sim._light, dtype=np.float64), room_table(layout),
            start_room, doors, env.pass_depth, sim.control_noise, sim.sensor_noise, sim.step_scale, sim.partial_moves,
            sim.sonar_radius, sim.edge_jump, sim.edge_both, env.binary_low, env.dock_tolerance, env.max_steps)


def sweep_arrays(n_obs: int) -> tuple:
    """The scan's and observation's arrays the loops fill: obs, collision, ranges, sonar, light, door."""
    return (np.empty(n_obs, dtype=np.float32), np.zeros(4, dtype=np.uint8), np.empty(N_RAYS), np.empty(N_RAYS),
            np.empty(N_RAYS, dtype=np.uint8), np.empty(N_RAYS, dtype=np.uint8))


@numba.njit(cache=False)
def _robot_step(world, a, pose, rng, sweep, feat, feat_true):
    """``RobotTaskEnv.step(a)`` after its checks: moves ``pose``, fills ``sweep`` (the observation first); returns
    (reward, success, collided, the contact's direction)."""
    (task, segs, kinds, lights, rooms, start_room, doors, pass_depth, control_noise, sensor_noise, step_scale,
     partial, sonar_radius, edge_jump, edge_both, low, dock_tolerance, env_max_steps) = world
    obs, collision, ranges, sonar, light, door = sweep
    collided, kind, rel = _act_and_sense(pose, a, rng, collision, segs, kinds, lights, control_noise, sensor_noise,
                                         step_scale, partial, sonar_radius, edge_jump, edge_both, ranges, sonar, light,
                                         door)
    success = False
    if task == 0:
        success = _docked(collided, a, kind, rel, dock_tolerance)
        reward = R_SUCCESS if success else (R_COLLISION if collided else 0.0)
    elif task == 1:
        success = not collided and _passed_door(pose[0], pose[1], _room(pose[0], pose[1], rooms), start_room,
                                                doors, pass_depth)
        reward = R_SUCCESS if success else (R_COLLISION if collided else 0.0)
    else:
        reward = _wf_reward(task, a, collided, ranges, feat_true)
    high = low + 1.0
    if task >= 2:
        _side_features(sonar if sonar_radius == ROBOT_RADIUS else sonar - (ROBOT_RADIUS - sonar_radius),
                       ROBOT_RADIUS, feat)
        _fill_obs(1, sonar, light, collision, low, high, feat, obs)
    else:
        _fill_obs(0, sonar, light if task == 0 else door, collision, low, high, feat, obs)
    return reward, success, collided, rel


@numba.njit(cache=False)
def _play_loop(qw1, qw2, qscale, qlinear, world, pose, trace, rng, sweep, feat, feat_true, max_steps, x, q):
    """The play from the world's state on (module docstring). Returns (steps, total reward, success, truncated,
    the last action); the arrays end as the world and learner leave them (``x``, ``q``: the last input acted on and
    its values; ``sweep``: the last observation and scan)."""
    h = np.empty(max(qw1.shape[1], 1))
    env_max_steps = world[-1]
    steps, total = 0, 0.0
    while True:
        _values_any(qw1, qw2, _as_input(sweep[0], x), h, qscale, q, qlinear)
        a = _greedy_choice(q)
        reward, success, _, _ = _robot_step(world, a, pose, rng, sweep, feat, feat_true)
        steps += 1
        trace[steps, 0], trace[steps, 1], trace[steps, 2] = pose[0], pose[1], pose[2]
        total += reward
        truncated = not success and (steps >= env_max_steps or steps >= max_steps)
        if success or truncated:
            return steps, total, success, truncated, a


def leave_sweep(env, pose, sweep, action, steps, trace) -> None:
    """The world and its simulator as ``run_trial`` leaves them (``leave``), with the last scan as its reading."""
    obs, collision, ranges, sonar, light, door = sweep
    leave(env, pose, collision, action, steps, trace)
    sim = env.sim
    env._reading = Reading(sonar, ranges, light, door, collision.copy(), sim.heading, sim.room, sim.sonar_radius)


def compiled(env, agent) -> bool:
    """Whether a test play of ``agent`` in ``env`` runs compiled: the plain case of the module docstring, with the
    shapes the loop indexes without bounds checked here (``run_trial`` would refuse a mismatch with a ValueError)."""
    return (type(env) is RobotTaskEnv and env.render_mode is None and type(env.sim) is RobotSim
            and type(agent) in (QCON, TeachingQCON) and agent.planner is None and type(agent.q) is OAON
            and agent.q.n_nets == N_ACTIONS and agent.q.config.n_inputs == OBS_SIZE[env.task] and hypot_matches())


def greedy_play(env: RobotTaskEnv, agent, seed: int, start, max_steps: int) -> TrialStats:
    """``run_trial(env, agent, trial=0, learning=False, seed=seed, options={"start": start}, max_steps=max_steps)``
    with ``compiled(env, agent)``; its stats' info holds "success" only."""
    obs, info = env.reset(seed=seed, options={"start": start})
    agent.begin_trial(obs, info, trial=0, learning=False)
    sim = env.sim
    sweep = sweep_arrays(len(obs))
    sweep[0][:] = obs
    pose = np.array(sim.pose, dtype=np.float64)
    trace = np.empty((env.max_steps + 1, 3))
    trace[0] = pose
    x, q = np.empty(obs.size), np.empty(agent.q.n_nets)
    steps, total, success, truncated, a = _play_loop(
        agent.q.w1, agent.q.w2, agent.q.scale, agent.q.config.linear_output, robot_world(env), pose, trace, sim.rng,
        sweep, env._feat, env._feat_true, max_steps, x, q)
    leave_sweep(env, pose, sweep, a, steps, trace)
    agent._x, agent.last_probabilities = x, boltzmann_probabilities(q, 0.0)
    agent.end_trial()
    return TrialStats(steps, total, bool(success), bool(truncated), {"success": bool(success)})
