"""Chs. 6 and 8's greedy test plays over behaviours, compiled whole (issue 45).

Ch. 6's protocol tests the high-level learner greedily on fixed tasks before the first trial and every few trials,
each step of a test going through a dozen Python calls: the learner's values and its Eq. 6.6 choice at T = 0, the
chosen behaviour's greedy primitive, the simulator's move and scan, the sensors' encodings and the applicability of
DK and DP (6.4.3). Here a test play runs as one Numba loop over the same kernels with the same arithmetic and the
same draws from the world's generator, step for step, as ``run_trial(env, agent, learning=False)``;
tests/tasks/test_recharge_play.py holds every play, and the world and learner it leaves, to ``run_trial``'s.

Exp. 1's plays without the hierarchy (a QCON over the primitive actions on the flat input, 6.6.1) are compiled the
same way (``greedy_play_flat``).

Only the plain case is compiled: a ``BehaviourEnv`` over a ``RechargeEnv`` with the 16 (or 14) high-level inputs,
behaviours that are a ``Behaviour`` over an ``OAON`` (the shipped library's, or Exp. 5's as they stand when tested)
and Ch. 6's ``BehaviourQCON`` with an ``OAON``; anything else plays through ``run_trial``. The robot's partial
moves divide by ``math.hypot``, whose CPython algorithm ``connrl.envs.robot.step`` ports and checks against the
running interpreter's once per process (``hypot_matches``); where they differ, every play goes through ``run_trial``.

The loop is not cached: it calls kernels of other files, and a cached kernel may only call its own file's
(tests/nets/test_kernel_cache.py); it compiles once per process.
"""

from __future__ import annotations

import numba
import numpy as np

from connrl.agents.behaviour_level import BehaviourChoice, BehaviourQCON
from connrl.agents.qcon import QCON
from connrl.agents.teaching import TeachingQCON
from connrl.core.exploration import boltzmann_probabilities
from connrl.core.rollout import TrialStats
from connrl.envs.robot.constants import (
    N_ACTIONS,
    N_RAYS,
    ROBOT_RADIUS,
    SONAR_MAX,
)
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, ROOMS, RechargeEnv, _scan_units
from connrl.envs.robot.sim import RobotSim
from connrl.envs.robot.step import _act_and_sense, _docked, _room, hypot_matches, leave, room_table
from connrl.envs.robot.tasks import OBS_SIZE, _fill_obs, _side_features
from connrl.nets import OAON
from connrl.nets.kernels import _values_any
from connrl.tasks.behaviours import APPLICABLE_ABOVE, Behaviour
from connrl.tasks.recharge import BehaviourEnv
from connrl.tasks.robot_play import _as_input, _greedy_choice


@numba.njit(cache=False)
def _first_max(q):
    """``np.argmax``: the first of equal maxima, the first NaN if there is one."""
    a = 0
    for k in range(q.size):
        if np.isnan(q[k]):
            return k
        if q[k] > q[a]:
            a = k
    return a


@numba.njit(cache=False)
def _greedy_applicable(q, applicable, acted):
    """``BehaviourChoice.choose`` at T = 0: the first best applicable behaviour (0 where an applicable value is NaN,
    as ``np.argmax`` of the all-False mask gives); the applicability it read is left in ``acted``."""
    b, best, nan = -1, 0.0, False
    for k in range(q.size):
        acted[k] = applicable[k]
        if applicable[k]:
            nan = nan or np.isnan(q[k])
            if b < 0 or q[k] > best:
                b, best = k, q[k]
    return 0 if nan else b


@numba.njit(cache=False)
def _observe(pose, room, collision, sonar, sonar_radius, light, door, low, xy_scale, size, room_bits, dk, dp, wf, top,
             feat):
    """``RechargeEnv._observe`` in "high" mode: the 16 high-level units into ``top``, Ch. 5's observations into
    ``dk``, ``dp`` and ``wf`` (float32, as the world hands them out)."""
    high = low + 1.0
    _scan_units(sonar, pose[2], collision, light, door, low, high, float(SONAR_MAX), top)
    code = room_bits[room] if room >= 0 else -1
    for r in range(3):
        top[11 + r] = high if code == r else low
    top[14] = xy_scale * (pose[0] / size[0] - 0.5)
    top[15] = xy_scale * (pose[1] / size[1] - 0.5)
    for k in range(4):
        feat[k] = 0.0
    _fill_obs(0, sonar, light, collision, low, high, feat, dk)
    _fill_obs(0, sonar, door, collision, low, high, feat, dp)
    body = sonar if sonar_radius == ROBOT_RADIUS else sonar - (ROBOT_RADIUS - sonar_radius)  # Reading.body_sonar
    _side_features(body, ROBOT_RADIUS, feat)
    _fill_obs(1, sonar, light, collision, low, high, feat, wf)


@numba.njit(cache=False)
def _applicable(w1s, w2s, scales, linears, thresholds, dk, dp, xdk, xdp, h, qdk, qdp, out):
    """6.4.3 for the state of ``dk``/``dp``: DK and DP apply where their largest value exceeds their threshold
    (``Behaviour.applicable``; NaN never does), wall following everywhere. DK's and DP's values are left in ``qdk``
    and ``qdp``: the nets do not change, so a choice of DK or DP in this state acts on them."""
    _values_any(w1s[0], w2s[0], _as_input(dk, xdk), h, scales[0], qdk, linears[0])
    _values_any(w1s[1], w2s[1], _as_input(dp, xdp), h, scales[1], qdp, linears[1])
    for b in range(2):
        qb = qdk if b == 0 else qdp
        ok, top = True, qb[0]
        for k in range(qb.size):
            ok = ok and not np.isnan(qb[k])
            top = max(top, qb[k])
        out[b] = ok and top > thresholds[b]
    out[2] = out[3] = True


@numba.njit(cache=False)
def _chg_step(pose, a, rng, collision, segs, kinds, lights, control_noise, sensor_noise, step_scale, partial,
              sonar_radius, edge_jump, edge_both, dock_tolerance, success_reward, collision_penalty, ranges, sonar,
              light, door):
    """``RechargeEnv.step``'s world part for primitive ``a``: the move after its draw, the scan after its 26, then
    docking (a forward move stopped head-on by the charger) and the reinforcement. Returns (collided, docked,
    reward)."""
    collided, kind, rel = _act_and_sense(pose, a, rng, collision, segs, kinds, lights, control_noise, sensor_noise,
                                         step_scale, partial, sonar_radius, edge_jump, edge_both, ranges, sonar, light,
                                         door)
    docked = _docked(collided, a, kind, rel, dock_tolerance)
    return collided, docked, success_reward if docked else (collision_penalty if collided else 0.0)


def _world(world: RechargeEnv) -> tuple:
    """What the loops read of the world: the simulator's surfaces and settings, the rooms, the sensors' settings, the
    reinforcement and the time limit (last)."""
    sim, layout = world.sim, world.layout
    room_bits = np.array([ROOMS.index(r) if r in ROOMS else -1 for r in layout.rooms], dtype=np.int64)
    return (sim._segs, sim._kinds, np.array(sim._light, dtype=np.float64), room_table(layout), room_bits,
            np.array(layout.size, dtype=np.float64), sim.control_noise, sim.sensor_noise, sim.step_scale,
            sim.partial_moves, sim.sonar_radius, sim.edge_jump, sim.edge_both, world.binary_low, world.xy_scale,
            world.dock_tolerance, world.success_reward, world.collision_penalty, world.max_steps)


def _state(obs, info, world: RechargeEnv) -> tuple:
    """The loops' world state from a reset: the learner's input, DK's, DP's and wall following's observations (as
    the world hands them out), the pose, the collision bits and the poses visited."""
    tasks = info["task_obs"]
    state = (np.array(obs, dtype=np.float32), *(np.array(tasks[t], dtype=np.float32) for t in ("DK", "DP", "WFL")),
             np.array(world.sim.pose, dtype=np.float64), np.zeros(4, dtype=np.uint8),
             np.empty((world.max_steps + 1, 3)))
    state[6][0] = state[4]
    return state


@numba.njit(cache=False)
def _senses():
    """The arrays ``_world_step`` fills: side features, ranges, sonar, light, door edges, the 16 high-level units."""
    return (np.zeros(4), np.empty(N_RAYS), np.empty(N_RAYS), np.empty(N_RAYS, dtype=np.uint8),
            np.empty(N_RAYS, dtype=np.uint8), np.empty(16, dtype=np.float32))


@numba.njit(cache=False)
def _world_step(a, world, state, rng, senses):
    """``RechargeEnv.step`` for primitive ``a`` (``_chg_step``), the pose visited and the new observations: DK's,
    DP's and wall following's into ``state``, the high-level units into ``senses``' last. Returns (collided, docked,
    reward, whether the robot changed rooms)."""
    (segs, kinds, lights, rooms, room_bits, size, control_noise, sensor_noise, step_scale, partial, sonar_radius,
     edge_jump, edge_both, low, xy_scale, dock_tolerance, success_reward, collision_penalty, _) = world
    _, dk, dp, wf, pose, collision, _ = state
    feat, ranges, sonar, light, door, top = senses
    before = _room(pose[0], pose[1], rooms)
    collided, docked, reward = _chg_step(pose, a, rng, collision, segs, kinds, lights, control_noise, sensor_noise,
                                         step_scale, partial, sonar_radius, edge_jump, edge_both, dock_tolerance,
                                         success_reward, collision_penalty, ranges, sonar, light, door)
    room = _room(pose[0], pose[1], rooms)
    _observe(pose, room, collision, sonar, sonar_radius, light, door, low, xy_scale, size, room_bits, dk, dp, wf, top,
             feat)
    return collided, docked, reward, room != before


@numba.njit(cache=False)
def _scan_arrays(lib, dk, dp, wf, n_hidden):
    """The arrays ``_behaviour_step`` fills (``_senses``' last), DK's and DP's values in the first state computed (as
    reset's)."""
    w1s, w2s, scales, linears, thresholds = lib
    h = np.empty(max(n_hidden, w1s[0].shape[1], w1s[1].shape[1], w1s[2].shape[1], w1s[3].shape[1], 1))
    scan = (np.empty(4, dtype=np.bool_), np.empty(dk.size), np.empty(dp.size), np.empty(wf.size), h,
            np.empty(w2s[0].shape[0]), np.empty(w2s[1].shape[0]), np.empty(w2s[2].shape[0]), _senses())
    _applicable(w1s, w2s, scales, linears, thresholds, dk, dp, scan[1], scan[2], h, scan[5], scan[6], scan[0])
    return scan


@numba.njit(cache=False)
def _behaviour_step(b, lib, world, state, rng, scan):
    """``BehaviourEnv.step(b)`` after its checks: the behaviour's greedy primitive, the world's step and the new
    state's observations and applicability (``scan[0]``). Returns (primitive, docked, reward, the behaviour's goal
    reached: DK docked, DP into another room without a collision, whether it collided)."""
    w1s, w2s, scales, linears, thresholds = lib
    obs, dk, dp, wf, _, _, _ = state
    applicable, xdk, xdp, xwf, h, qdk, qdp, qwf, senses = scan
    if b >= 2:
        _values_any(w1s[b], w2s[b], _as_input(wf, xwf), h, scales[b], qwf, linears[b])
    prim = _first_max(qdk if b == 0 else qdp if b == 1 else qwf)
    collided, docked, reward, moved = _world_step(prim, world, state, rng, senses)
    top = senses[5]
    for k in range(obs.size):
        obs[k] = top[k]
    _applicable(w1s, w2s, scales, linears, thresholds, dk, dp, xdk, xdp, h, qdk, qdp, applicable)
    goal = docked if b == 0 else (b == 1 and not collided and moved)
    return prim, docked, reward, goal, collided


@numba.njit(cache=False)
def _play_loop(qnet, lib, world, state, rng, x, q, acted):
    """The play from the world's state on (module docstring), until it docks or times out: ``qnet`` is the learner's
    OAON ``(w1, w2, scale, linear)``, ``lib`` ``library_arrays``', ``world`` ``_world``'s, ``state`` ``_state``'s.
    Returns (steps, total reward, docked, collided steps, the last behaviour, the last primitive action); the arrays
    end as the world and learner leave them (``x``, ``q``, ``acted``: the last input the learner acted on, its values
    and the applicability its choice read). The behaviour's step is written out here rather than called
    (``_behaviour_step``): called, it cost this loop 5-10% (docs/PERFORMANCE.md, issue 46's last round)."""
    qw1, qw2, qscale, qlinear = qnet
    w1s, w2s, scales, linears, thresholds = lib
    (segs, kinds, lights, rooms, room_bits, size, control_noise, sensor_noise, step_scale, partial, sonar_radius,
     edge_jump, edge_both, low, xy_scale, dock_tolerance, success_reward, collision_penalty, max_steps) = world
    obs, dk, dp, wf, pose, collision, trace = state
    scan = _scan_arrays(lib, dk, dp, wf, qw1.shape[1])
    applicable, xdk, xdp, xwf, h, qdk, qdp, qwf, senses = scan
    feat, ranges, sonar, light, door, top = senses
    steps, total, hits, prim = 0, 0.0, 0, -1
    while True:
        # BehaviourQCON.act(greedy=True): the first best applicable behaviour (Eq. 6.6 at T = 0)
        _values_any(qw1, qw2, _as_input(obs, x), h, qscale, q, qlinear)
        b = _greedy_applicable(q, applicable, acted)
        if b >= 2:
            _values_any(w1s[b], w2s[b], _as_input(wf, xwf), h, scales[b], qwf, linears[b])
        # BehaviourEnv.step: the behaviour's greedy primitive, the world's step
        prim = _first_max(qdk if b == 0 else qdp if b == 1 else qwf)
        collided, docked, reward = _chg_step(pose, prim, rng, collision, segs, kinds, lights, control_noise,
                                             sensor_noise, step_scale, partial, sonar_radius, edge_jump, edge_both,
                                             dock_tolerance, success_reward, collision_penalty, ranges, sonar, light,
                                             door)
        steps += 1
        trace[steps, 0], trace[steps, 1], trace[steps, 2] = pose[0], pose[1], pose[2]
        _observe(pose, _room(pose[0], pose[1], rooms), collision, sonar, sonar_radius, light, door, low, xy_scale,
                 size, room_bits, dk, dp, wf, top, feat)
        for k in range(obs.size):
            obs[k] = top[k]
        _applicable(w1s, w2s, scales, linears, thresholds, dk, dp, xdk, xdp, h, qdk, qdp, applicable)
        total += reward
        hits += collided
        if docked or steps >= max_steps:
            return steps, total, docked, hits, b, prim


def compiled(env, agent) -> bool:
    """Whether a test play of ``agent`` in ``env`` runs compiled: the plain case of the module docstring, with every
    shape the loop indexes without bounds checked here (``run_trial`` would refuse a mismatch with a ValueError)."""
    if type(agent) is not BehaviourQCON or type(agent.q) is not OAON or type(agent.choice) is not BehaviourChoice:
        return False
    return (agent.q.n_nets == len(BEHAVIOUR_TASKS) and type(env) is BehaviourEnv
            and agent.q.config.n_inputs == env.world.observation_space.shape[0] and compiled_world(env))


def compiled_world(env) -> bool:
    """Whether the loops can play ``env``: a ``BehaviourEnv`` over a plain ``RechargeEnv`` with the high-level inputs
    and a library of plain behaviours whose nets fit their tasks' observations, where the ported ``hypot`` holds."""
    if type(env) is not BehaviourEnv:
        return False
    world = env.world
    if type(world) is not RechargeEnv or world.obs_mode != "high" or type(world.sim) is not RobotSim:
        return False
    for t in BEHAVIOUR_TASKS:
        b = env.library[t]
        if type(b) is not Behaviour or type(b.q) is not OAON or b.task != t or b.q.n_nets != N_ACTIONS or (
                b.q.config.n_inputs != OBS_SIZE[t]):
            return False
    return hypot_matches()


def greedy_play(env: BehaviourEnv, agent: BehaviourQCON, seed: int, start) -> tuple[TrialStats, int]:
    """``run_trial(env, agent, trial=0, learning=False, seed=seed, options={"start": start})`` with
    ``compiled(env, agent)``; returns its stats (their info holds "success" only) and the number of steps with a
    collision."""
    obs, info = env.reset(seed=seed, options={"start": start})
    agent.begin_trial(obs, info, trial=0, learning=False)
    state = _state(obs, info, env.world)
    x, q, acted = np.empty(len(obs)), np.empty(agent.q.n_nets), np.empty(4, dtype=np.bool_)
    qnet = (agent.q.w1, agent.q.w2, agent.q.scale, agent.q.config.linear_output)
    steps, total, docked, hits, _, prim = _play_loop(qnet, library_arrays(env), _world(env.world), state,
                                                     env.world.sim.rng, x, q, acted)
    _, dk, dp, wf, pose, collision, trace = state
    _leave(env, agent, steps, pose, collision, prim, trace, dk, dp, wf, x, q, acted)
    info = {"success": bool(docked)}
    return TrialStats(steps, total, bool(docked), not docked, info), hits


def library_arrays(env) -> tuple:
    """The behaviours as ``recharge_play``'s kernels read them (DK, DP, WFL, WFR)."""
    lib = [env.library[t] for t in BEHAVIOUR_TASKS]
    return (tuple(b.q.w1 for b in lib), tuple(b.q.w2 for b in lib), np.array([b.q.scale for b in lib]),
            np.array([b.q.config.linear_output for b in lib]), np.array([APPLICABLE_ABOVE[t] for t in BEHAVIOUR_TASKS]))


def _leave(env, agent, steps, pose, collision, prim, trace, dk, dp, wf, x, q, acted) -> None:
    """Leave the world and the learner as ``run_trial`` does (but for the learner's record of the trial's choices,
    ``agent.choice``, which a test trial never reads and the next trial begins anew)."""
    leave(env.world, pose, collision, prim, steps, trace)
    env._task_obs = {"DK": dk, "DP": dp, "WFL": wf, "WFR": wf.copy()}
    agent._x, agent.last_q = x, q
    best = acted & (q == q[acted].max())
    agent.last_probabilities = best / best.sum()
    agent.end_trial()


# ------------------------------------------------------------------ Exp. 1: QCON over primitives on the flat input

@numba.njit(cache=False)
def _flat_loop(qnet, world, state, rng, x, q):
    """Exp. 1's test play (6.6.1): the learner's greedy primitive on the flat input, the world's step, the flat
    input again (``RechargeEnv._observe``: DK's sonar and light, DP's door edges, the collision bits, wall following's
    parallelism and clearance bits, then the high-level units). Arguments as ``_play_loop``'s; returns (steps, total
    reward, docked, collided steps, the last action)."""
    qw1, qw2, qscale, qlinear = qnet
    obs, dk, dp, wf, pose, _, trace = state
    h, senses = np.empty(max(qw1.shape[1], 1)), _senses()
    top = senses[5]
    steps, total, hits, max_steps = 0, 0.0, 0, world[-1]
    while True:
        _values_any(qw1, qw2, _as_input(obs, x), h, qscale, q, qlinear)
        a = _greedy_choice(q)
        collided, docked, reward, _ = _world_step(a, world, state, rng, senses)
        steps += 1
        trace[steps, 0], trace[steps, 1], trace[steps, 2] = pose[0], pose[1], pose[2]
        obs[0:48], obs[48:72], obs[72:76], obs[76:84] = dk[0:48], dp[24:48], dk[48:52], wf[28:36]
        for k in range(84, obs.size):
            obs[k] = top[k - 84]
        total += reward
        hits += collided
        if docked or steps >= max_steps:
            return steps, total, docked, hits, a


def compiled_flat(env, agent) -> bool:
    """Whether Exp. 1's test play of ``agent`` in ``env`` runs compiled: a plain ``RechargeEnv`` with the flat input
    and a QCON (or QCON-T) over an ``OAON`` with no planner whose nets fit it."""
    return (type(env) is RechargeEnv and env.obs_mode == "flat" and type(env.sim) is RobotSim
            and type(agent) in (QCON, TeachingQCON) and agent.planner is None and type(agent.q) is OAON
            and agent.q.n_nets == N_ACTIONS and agent.q.config.n_inputs == env.observation_space.shape[0]
            and hypot_matches())


def greedy_play_flat(env: RechargeEnv, agent, seed: int, start) -> tuple[TrialStats, int]:
    """``run_trial(env, agent, trial=0, learning=False, seed=seed, options={"start": start})`` with
    ``compiled_flat(env, agent)``; returns its stats (their info holds "success" only) and the steps with a
    collision."""
    obs, info = env.reset(seed=seed, options={"start": start})
    agent.begin_trial(obs, info, trial=0, learning=False)
    state = _state(obs, info, env)
    x, q = np.empty(len(obs)), np.empty(agent.q.n_nets)
    qnet = (agent.q.w1, agent.q.w2, agent.q.scale, agent.q.config.linear_output)
    steps, total, docked, hits, a = _flat_loop(qnet, _world(env), state, env.sim.rng, x, q)
    _, _, _, _, pose, collision, trace = state
    leave(env, pose, collision, a, steps, trace)
    agent._x, agent.last_probabilities = x, boltzmann_probabilities(q, 0.0)
    agent.end_trial()
    return TrialStats(steps, total, bool(docked), not docked, {"success": bool(docked)}), hits
