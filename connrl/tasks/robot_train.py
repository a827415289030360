"""Ch. 5's training trials compiled whole (issue 45).

A training trial of Ch. 5's QCON-T (5.3) is, step by step: the nets' values, the temperature with stuck detection
(5.3.4), the Boltzmann choice on Q / 100, the simulator's move and scan, the task's reinforcement and observation, the
on-line Q-learning update and the experience filed for replay. ``learning_play`` runs all of it as one Numba loop,
with the same arithmetic and the same draws from the agent's and the world's generators as
``run_trial(env, agent, learning=True)``; the lesson and the replays after the trial are the Python path's own.
tests/tasks/test_robot_train.py holds the two to each other, nets and streams bit for bit.

Compiled where a greedy test play is (``connrl.tasks.robot_play.compiled``) and the learner explores as
``LessonAgent`` does (``Exploration`` with or without a ``StuckDetector``, a temperature above 0); anything else (a
method replaced on the instance too), and a trial watched step by step (``on_step``), plays through ``run_trial``.
Not cached, as ``connrl.tasks.robot_play``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from connrl.agents.base import Exploration, methods_replaced
from connrl.core.boltzmann_kernel import _boltzmann_choice, _nanmax, compiled_choice_fits
from connrl.core.exploration import StuckDetector
from connrl.core.rollout import TrialStats, run_trial
from connrl.envs.robot.sim import collision_side
from connrl.nets.kernels import _update_any, _values_any
from connrl.tasks.robot_play import _as_input, _robot_step, compiled, leave_sweep, robot_world, sweep_arrays


def compiled_learning(env, agent, trial: int) -> bool:
    """Whether ``learning_play`` compiles this trial (the module docstring's cases)."""
    ex, rec = agent.explore, agent.book.recorder
    d = ex.detector
    return (compiled(env, agent) and agent.n_actions == agent.q.n_nets and type(ex) is Exploration
            and ex.schedule(trial) > 0
            and not methods_replaced(agent)
            and (d is None or (type(d) is StuckDetector and type(d.config.window) is int and d.config.window >= 1
                              and d.config.boost > 0))
            and rec.empty() and compiled_choice_fits(agent.n_actions))


def learning_play(env, agent, *, trial: int, seed: int | None = None, options: dict | None = None,
                  on_step=None) -> TrialStats:
    """``run_trial(env, agent, trial=trial, learning=True, seed=seed, options=options, on_step=on_step)``, compiled
    when ``on_step`` is None and ``compiled_learning(env, agent)``."""
    if on_step is not None or not compiled_learning(env, agent, trial):
        return run_trial(env, agent, trial=trial, learning=True, seed=seed, options=options, on_step=on_step)
    obs, info = env.reset(seed=seed, options=options)
    agent.begin_trial(obs, info, trial=trial, learning=True)
    sim, q, c, d = env.sim, agent.q, agent.config, agent.explore.detector
    sweep = sweep_arrays(len(obs))
    sweep[0][:] = obs
    pose = np.array(sim.pose, dtype=np.float64)
    cap = env.max_steps  # the world's time limit ends every trial
    trace, inputs = np.empty((cap + 1, 3)), np.empty((cap + 1, q.config.n_inputs))
    trace[0], inputs[0] = pose, agent._x
    actions, rewards = np.empty(cap, np.int64), np.empty(cap)
    window = d.config.window if d is not None else 1
    history = np.zeros((window, 2))
    for i, p in enumerate(d._pos if d is not None else []):
        history[i] = p
    count = np.array([len(d._pos) if d is not None else 0])
    stuck = (d is not None, window, d.config.radius if d is not None else 0.0, d.config.boost if d is not None else 1.0,
             history, count)
    learner = (agent.explore.base, agent.merit_scale, c.online, c.gamma, 0.0 if c.target_clip is None else
               c.target_clip, c.target_clip is not None, q.scale, q.lr, q.config.momentum, q.config.linear_output)
    p = np.empty(agent.n_actions)
    state = (pose, trace, sweep, env._feat, env._feat_true)
    steps, total, success, a, collided, rel = _learning_loop(
        (q.w1, q.w2, q.d1, q.d2), learner, stuck, agent.rng, robot_world(env), state, (inputs, actions, rewards),
        sim.rng, np.empty(agent.n_actions), p, np.zeros(5, np.int64))
    leave_sweep(env, pose, sweep, a, steps, trace)
    agent.took_compiled_trial(inputs[:steps + 1], actions[:steps], rewards[:steps], success, p)
    if d is not None:
        d._pos = [history[i].copy() for i in range(int(count[0]))]
    info = env._info(sim.room, success, collided, collision_side(rel) if collided else -1)
    agent.end_trial()
    agent.learn()
    return TrialStats(steps, total, bool(success), not success, info)


NOT_RESTRICTED = np.zeros(0, dtype=np.bool_)  # _online_q_step's ``allowed`` where the max ranges over every net


@numba.njit(cache=False)
def _online_q_step(w1, w2, d1, d2, a, x, y, terminal, reward, gamma, clip, has_clip, h, qn, scale, lr, momentum,
                   linear, allowed, restrict):
    """Fig. 3.4 steps 4-5 after a step from ``x`` by action ``a`` to ``y``, as ``QCON.observe`` makes them: the target
    ``reward + gamma * max Q(y)`` (0 for the max at a terminal state; NaN propagates as in ``np.max``), over the nets
    ``allowed`` when ``restrict`` (``BehaviourChoice.next_value``), cut off at ``clip`` when ``has_clip``
    (``online_target``), then net a's update toward it. ``qn``: scratch for Q(y)."""
    nxt = 0.0
    if not terminal:
        _values_any(w1, w2, y, h, scale, qn, linear)
        nxt = _nanmax(qn, qn.size)
        if restrict:  # q_next[allowed].max()
            nxt, seen = 0.0, False
            for k in range(qn.size):
                if allowed[k] and (not seen or qn[k] > nxt or qn[k] != qn[k]) and nxt == nxt:
                    nxt, seen = qn[k], True
    target = reward + gamma * nxt
    target = clip if has_clip and clip < target else target
    _update_any(w1, w2, d1, d2, a, x, h, target, scale, lr, momentum, linear)


@numba.njit(cache=False)
def _stuck_factor(x, y, history, count, window, radius, boost):
    """``StuckDetector.factor((x, y))``: record the position (the last ``window`` kept, oldest first, ``count[0]`` of
    them) and return ``boost`` when all lie within ``radius`` of their mean, else 1."""
    if count[0] == window:
        for i in range(window - 1):
            history[i, 0], history[i, 1] = history[i + 1, 0], history[i + 1, 1]
        count[0] -= 1
    history[count[0], 0], history[count[0], 1] = x, y
    count[0] += 1
    if count[0] < window:
        return 1.0
    mx, my = 0.0, 0.0
    for i in range(window):  # p.mean(axis=0): the rows summed in order
        mx += history[i, 0]
        my += history[i, 1]
    mx, my = mx / window, my / window
    spread = -1.0
    for i in range(window):  # np.linalg.norm(p - mean, axis=1).max()
        dx, dy = history[i, 0] - mx, history[i, 1] - my
        r = math.sqrt(dx * dx + dy * dy)
        if r > spread or r != r:
            spread = r
    return boost if spread <= radius else 1.0


@numba.njit(cache=False)
def _learning_loop(net, learner, stuck, agent_rng, world, state, record, rng, q, p, scratch):
    """The trial from ``inputs[0]`` on: QCON's act and observe (Fig. 3.4) around the world's step, until success or
    the time limit. Returns (steps, total reward, success, the last action, whether it collided, the contact's
    direction); the experiences are left in ``inputs``/``actions``/``rewards``, the last choice's distribution in
    ``p``. ``net`` is the OAON's ``(w1, w2, d1, d2)``, ``stuck`` the detector's settings and its history of
    positions, ``state`` the world's pose, poses visited and sensor arrays, ``record`` the trial's experiences."""
    w1, w2, d1, d2 = net
    base, merit_scale, online, gamma, clip, has_clip, scale, lr, momentum, linear = learner
    detect, window, radius, boost, history, count = stuck
    pose, trace, sweep, feat, feat_true = state
    inputs, actions, rewards = record
    h = np.empty(max(w1.shape[1], 1))
    env_max_steps = world[-1]
    steps, total = 0, 0.0
    while True:
        x, y = inputs[steps], inputs[steps + 1]
        factor = _stuck_factor(pose[0], pose[1], history, count, window, radius, boost) if detect else 1.0
        t = base * factor * merit_scale
        _values_any(w1, w2, x, h, scale, q, linear)
        a = _boltzmann_choice(q, t, agent_rng, p, scratch)
        reward, success, collided, rel = _robot_step(world, a, pose, rng, sweep, feat, feat_true)
        steps += 1
        trace[steps, 0], trace[steps, 1], trace[steps, 2] = pose[0], pose[1], pose[2]
        _as_input(sweep[0], y)
        actions[steps - 1], rewards[steps - 1] = a, reward
        total += reward
        if online:
            _online_q_step(w1, w2, d1, d2, a, x, y, success, reward, gamma, clip, has_clip, h, q, scale, lr, momentum,
                           linear, NOT_RESTRICTED, False)
        if success or steps >= env_max_steps:
            return steps, total, success, a, collided, rel
