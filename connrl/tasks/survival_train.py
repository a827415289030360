"""Ch. 4's training plays compiled whole (issue 45).

A training play of QCON or AHCON (Figs. 3.2, 3.4) is, step by step: the net's values at the input, the temperature
with the survival task's stuck detection (4.2.6), the Boltzmann choice, the world's step and sensing, the on-line
update, and the experience filed for replay. ``learning_play`` runs all of it as one Numba loop, with the same
arithmetic and the same draws from both generators as ``run_trial(env, agent, learning=True)``; the lesson, the
learner's state and the replay after the play are then the Python path's own (``agent.end_trial()``,
``agent.learn()``). tests/tasks/test_survival_train.py holds the two to each other, nets and streams bit for bit.

Compiled: QCON and AHCON learning on-line, with a rotated net or one net per action (both with a hidden layer), on a
plain ``SurvivalEnv``, without a planner or with the relaxation planner of a survival model of that world
(``connrl.tasks.survival_planning``) -- every agent ``make_survival_agent`` builds. Anything else (another class, a
method replaced on the instance, a wrapped world, a temperature of 0) plays through ``run_trial``, as does
everything where the choice's ``exp``, its sums or the stuck test's ``hypot`` cannot be had bit for bit
(``compiled_choice_fits``, ``hypot_matches``).

The loop is not cached: it compiles in kernels of other files (tests/nets/test_kernel_cache.py).
"""

from __future__ import annotations

import numba
import numpy as np

from connrl.agents.ahcon import AHCON
from connrl.agents.base import methods_replaced
from connrl.agents.qcon import QCON
from connrl.core.boltzmann_kernel import _boltzmann_choice, _nanmax, compiled_choice_fits
from connrl.core.rollout import TrialStats, run_trial
from connrl.envs.robot.step import _hypot, hypot_matches
from connrl.envs.survival.env import SurvivalEnv
from connrl.envs.survival.world import FOOD_ENERGY, N_INPUTS
from connrl.nets.mlp import OAON
from connrl.nets.rotated import RotatedNet
from connrl.tasks.survival import SurvivalExploration
from connrl.tasks.survival_planning import (
    _model_learn,
    _plan,
    _update,
    _value,
    _values,
    leave_planning,
    plan_buffers,
    plan_fits,
    planning_of,
)
from connrl.tasks.survival_play import _world_step, world_of


def _net_of(net) -> tuple | None:
    """What the loop reads of a Q- or policy net: (w1, w2, d1, d2, h, xr, perms, scale, lr, momentum, rotated), or
    None for a net it does not compile."""
    if type(net) is RotatedNet:
        o = net.net
        return (o.w1, o.w2, o.d1, o.d2, o._h, net._xr, net.perms, o.scale, o.lr, net.config.momentum, True)
    if type(net) is OAON and net.config.n_hidden > 0:
        return (net.w1, net.w2, net.d1, net.d2, net._h, np.empty(0), np.empty((0, 0), np.int64), net.scale, net.lr,
                net.config.momentum, False)
    return None


def _compiled_nets(env, agent, trial: int) -> tuple[tuple, tuple | None] | None:
    """(the choosing net, AHCON's V-net or None) when ``learning_play`` compiles this agent's play, else None."""
    if (type(env) is not SurvivalEnv or type(agent) not in (QCON, AHCON) or not plan_fits(agent, env)
            or methods_replaced(agent)):
        return None
    ex, rec = agent.explore, agent.book.recorder
    if (not agent.config.online or type(ex) is not SurvivalExploration or not ex.schedule(trial) > 0
            or not ex.stuck.boost > 0
            or ex.stuck.window < 1 or not rec.empty() or not compiled_choice_fits(agent.n_actions)
            or not hypot_matches()):
        return None
    if type(agent) is QCON:
        net, v = _net_of(agent.q), None
    else:
        net, v = _net_of(agent.policy), _net_of(agent.v)
        if v is None or v[-1] or v[0].shape[0] != 1:
            return None
    if net is None or (net[6].shape[0] if net[-1] else net[0].shape[0]) != agent.n_actions:
        return None
    if any(n[0].shape[2] != N_INPUTS + 1 for n in (net, v) if n is not None):
        return None  # the loop indexes without bounds checks; run_trial refuses a net of another input size
    return net, v


def learning_play(env, agent, *, trial: int, seed: int | None = None, options: dict | None = None) -> TrialStats:
    """``run_trial(env, agent, trial=trial, learning=True, seed=seed, options=options)``, compiled for the agents
    and worlds the module docstring names."""
    nets = _compiled_nets(env, agent, trial)
    if nets is None:
        return run_trial(env, agent, trial=trial, learning=True, seed=seed, options=options)
    net, v = nets
    obs, info = env.reset(seed=seed, options=options)
    agent.begin_trial(obs, info, trial=trial, learning=True)
    ex, c = agent.explore, agent.explore.stuck
    # a play ends by the time it has spent its energy: one unit a step, FOOD_ENERGY more for each food eaten
    cap = int(env._s[0]) + FOOD_ENERGY * int(env._s[5])
    cap = max(1, cap if env.max_steps is None else min(cap, env.max_steps))
    inputs, actions, rewards = np.empty((cap + 1, N_INPUTS)), np.empty(cap, np.int64), np.empty(cap)
    inputs[0] = agent._x
    rows, cols = np.zeros(c.window), np.zeros(c.window)
    rows[:len(ex._rows)], cols[:len(ex._cols)] = ex._rows, ex._cols
    stuck = np.array([len(ex._rows), ex._food, ex.boosted], np.int64)
    gamma, clip = agent.config.gamma, agent.config.target_clip
    learner = (gamma, 0.0 if clip is None else clip, clip is not None, ex.base, agent.merit_scale,
               c.window, c.radius, c.boost)
    planning, bufs = planning_of(agent, env, trial, cap), plan_buffers(agent.n_actions)
    steps, total, terminated = _learning_loop(
        net, net if v is None else v, v is not None, learner, rows, cols, stuck, agent.rng, inputs, actions, rewards,
        np.empty(agent.n_actions), bufs, world_of(env), planning)
    if steps < 0:
        raise RuntimeError(f"a survival play outlasted its energy bound of {cap} steps")
    env._done = True
    leave_planning(agent, planning)
    agent.took_compiled_trial(inputs[:steps + 1], actions[:steps], rewards[:steps], terminated, bufs[5].copy())
    n, ex = int(stuck[0]), agent.explore  # the stuck detector's history
    ex._rows, ex._cols, ex._food, ex.boosted = rows[:n].tolist(), cols[:n].tolist(), int(stuck[1]), int(stuck[2])
    agent.end_trial()
    agent.learn()
    return TrialStats(steps, total, bool(terminated), not terminated, env._info())


@numba.njit(cache=False)
def _stuck_factor(r, c, food_eaten, window, radius, boost, rows, cols, stuck):
    """``SurvivalExploration.temperature``'s factor on the trial's T (4.2.6): 1, or ``boost`` while the last
    ``window`` positions since the last food lie within ``radius`` of their mean. ``rows``/``cols`` hold them,
    oldest first; ``stuck`` is [how many, food eaten when they began, steps boosted this play]."""
    if food_eaten != stuck[1]:
        stuck[0], stuck[1] = 0, food_eaten
    if stuck[0] == window:
        for i in range(window - 1):
            rows[i], cols[i] = rows[i + 1], cols[i + 1]
        stuck[0] -= 1
    rows[stuck[0]], cols[stuck[0]] = r, c
    stuck[0] += 1
    if stuck[0] < window:
        return 1.0
    mr, mc = 0.0, 0.0
    for i in range(window):  # whole cells: every order of the sum gives the same bits
        mr += rows[i]
        mc += cols[i]
    mr, mc = mr / window, mc / window
    for i in range(window):
        if not _hypot(rows[i] - mr, cols[i] - mc) <= radius:
            return 1.0
    stuck[2] += 1
    return boost


@numba.njit(cache=False)
def _learning_loop(net, v, ahcon, learner, rows, cols, stuck, rng, inputs, actions, rewards, q, bufs, world,
                   planning):
    """The play from ``inputs[0]`` on: QCON's (``ahcon`` False) or AHCON's act (with the planner's look-ahead first,
    when it plans), the world's step and observe, until the play ends or ``inputs`` is full (steps returned as -1).
    Returns (steps, total reward, terminated); the experiences are left in ``inputs``/``actions``/``rewards``, the
    last choice's distribution in ``bufs[5]``."""
    gamma, clip, has_clip, base_t, merit_scale, window, radius, boost = learner
    pos, s, p, scratch = world[4], world[5], bufs[5], bufs[8]
    first = planning[5][3]  # the learned model's experiences before this play
    steps, total = 0, 0.0
    while steps < actions.size:
        x, y = inputs[steps], inputs[steps + 1]
        t = base_t * _stuck_factor(float(pos[0]), float(pos[1]), s[4], window, radius, boost, rows, cols, stuck)
        t *= merit_scale
        _values(net, x, q)
        if _plan(net, v, ahcon, x, q, t, gamma, clip, has_clip, world, planning, bufs):
            _values(net, x, q)  # plan before choosing (3.6.1)
        a = _boltzmann_choice(q, t, rng, p, scratch)
        reward, terminated, truncated = _world_step(world, a, y)
        actions[steps], rewards[steps] = a, reward
        steps += 1
        total += reward
        if ahcon:  # Fig. 3.2 steps 4-6
            target = reward + gamma * (0.0 if terminated else _value(v, y))
            target = clip if has_clip and clip < target else target
            e = _update(v, x, 0, target, False)
            _update(net, x, a, target - e, True)
        else:  # Fig. 3.4 steps 4-5
            if terminated:
                target = reward + gamma * 0.0
            else:
                _values(net, y, q)
                target = reward + gamma * _nanmax(q, q.size)
            target = clip if has_clip and clip < target else target
            _update(net, x, a, target, False)
        if planning[2]:  # a learned model trains on-line (4.2.5)
            _model_learn(x, a, reward, y, planning, rng, bufs, first)
        if terminated or truncated:
            return steps, total, terminated
    return -1, total, False
