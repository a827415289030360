"""Chs. 6 and 8's training trials over behaviours compiled whole (issue 45).

A training trial of the high-level learner (6.5-6.6, 8.3) is, step by step: the Q-values, Eq. 6.6's weighted choice
(W from applicability and, in Experiment 3, persistence), the chosen behaviour's greedy primitive, the simulator's move
and scan, the sensors' encodings and DK's and DP's applicability (6.4.3), then, for Ch. 6's ``BehaviourQCON``, the
on-line update (its target's max over all behaviours or the applicable ones); Ch. 8's ``BehaviourRecurrentQ`` moves
its context on instead. ``learning_play`` runs all of it as one Numba loop with the same arithmetic and the same draws
from the learner's and the world's generators as ``run_trial(env, agent, learning=True)``; the lesson (with each
step's W and each state's applicability), the trial's end and the replays are the Python path's own. Ch. 8's greedy
test plays of recurrent-Q are compiled here too (``greedy_play``; ``recharge_play`` compiles Ch. 6's).
tests/tasks/test_recharge_train.py holds the two to each other, nets and streams bit for bit.

Compiled where a greedy test play is (``connrl.tasks.recharge_play``: a ``BehaviourEnv`` over a plain world and
library) for a ``BehaviourQCON`` over an ``OAON`` without a planner or a ``BehaviourRecurrentQ`` over a
``RecurrentOAON``, both with a ``BehaviourChoice``, exploring without stuck detection at a temperature above 0;
anything else (a method replaced on the instance too), and a trial watched step by step (``on_step``), plays through
``run_trial``. The returned stats' info holds "success" only. Not cached, as ``connrl.tasks.recharge_play``.
"""

from __future__ import annotations

import numba
import numpy as np

from connrl.agents.base import Exploration, methods_replaced
from connrl.agents.behaviour_level import BehaviourChoice, BehaviourQCON, BehaviourRecurrentQ
from connrl.core.boltzmann_kernel import _weighted_choice, weighted_choice_fits
from connrl.core.rollout import TrialStats, run_trial
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS
from connrl.envs.robot.step import leave
from connrl.nets import OAON
from connrl.nets.kernels import _forward_all, _values_any
from connrl.nets.recurrent import RecurrentOAON
from connrl.tasks.recharge_play import (
    _behaviour_step,
    _greedy_applicable,
    _scan_arrays,
    _state,
    _world,
    compiled_world,
    library_arrays,
)
from connrl.tasks.robot_play import _as_input
from connrl.tasks.robot_train import _online_q_step


def compiled_learning(env, agent, trial: int) -> bool:
    """Whether ``learning_play`` compiles this trial (the module docstring's cases)."""
    if type(agent) is BehaviourQCON:
        nets = type(agent.q) is OAON and agent.planner is None and agent.q.n_nets == len(BEHAVIOUR_TASKS)
        n_inputs = agent.q.config.n_inputs
    elif type(agent) is BehaviourRecurrentQ:
        net = agent.net
        nets = type(net) is RecurrentOAON and net.config.n_outputs == 1 and net.n_nets == len(BEHAVIOUR_TASKS)
        n_inputs = net.config.n_inputs
    else:
        return False
    ex = agent.explore
    return (nets and compiled_world(env) and n_inputs == env.observation_space.shape[0]
            and agent.n_actions == len(BEHAVIOUR_TASKS) and type(agent.choice) is BehaviourChoice
            and type(ex) is Exploration and ex.detector is None and ex.schedule(trial) > 0
            and not methods_replaced(agent) and agent.book.recorder.empty()
            and weighted_choice_fits(len(BEHAVIOUR_TASKS)))


def learning_play(env, agent, *, trial: int, seed: int | None = None, options: dict | None = None,
                  on_step=None) -> TrialStats:
    """``run_trial(env, agent, trial=trial, learning=True, seed=seed, options=options, on_step=on_step)``, compiled
    when ``on_step`` is None and ``compiled_learning(env, agent, trial)``."""
    if on_step is not None or not compiled_learning(env, agent, trial):
        return run_trial(env, agent, trial=trial, learning=True, seed=seed, options=options, on_step=on_step)
    obs, info = env.reset(seed=seed, options=options)
    agent.begin_trial(obs, info, trial=trial, learning=True)
    world, choice, cap = env.world, agent.choice, env.world.max_steps
    state = _state(obs, info, world)
    n = len(BEHAVIOUR_TASKS)
    inputs, actions, rewards = np.empty((cap + 1, len(obs))), np.empty(cap, np.int64), np.empty(cap)
    weights, applicable = np.empty((cap, n)), np.empty((cap + 1, n), dtype=np.bool_)
    inputs[0], applicable[0] = agent._x, info["applicable"]
    record = (inputs, actions, rewards, weights, applicable)
    rule = (choice.persistence, choice.persist_weight, choice.target_max == "applicable",
            agent.explore.base * agent.merit_scale)
    q, p, scratch = np.empty(n), np.empty(n), np.zeros(5, np.int64)
    if type(agent) is BehaviourQCON:
        net, c = agent.q, agent.config
        learner = (c.online, c.gamma, 0.0 if c.target_clip is None else c.target_clip, c.target_clip is not None,
                   net.scale, net.lr, net.config.momentum, net.config.linear_output)
        steps, total, docked, b, prim = _qcon_loop((net.w1, net.w2, net.d1, net.d2), learner, rule,
                                                   library_arrays(env), _world(world), state, record, agent.rng,
                                                   world.sim.rng, q, p, np.empty(n), scratch)
    else:
        steps, total, docked, b, prim = _recurrent_loop(agent.net.play_arrays, rule, library_arrays(env),
                                                        _world(world), state, record, agent.rng, world.sim.rng, q, p,
                                                        scratch)
    if steps < 0:
        raise ValueError("Probabilities contain NaN")  # as Generator.choice refuses Eq. 6.6's NaN distribution
    _, dk, dp, wf, pose, collision, trace = state
    leave(world, pose, collision, prim, steps, trace)
    env._task_obs = {"DK": dk, "DP": dp, "WFL": wf, "WFR": wf.copy()}
    agent.took_compiled_trial(inputs[:steps + 1], actions[:steps], rewards[:steps], docked, p)
    agent.last_q = q
    if type(agent) is BehaviourRecurrentQ:
        agent._x = inputs[steps - 1].copy()  # the input of its last choice: recurrent-Q's observe keeps none
    choice._active, choice._was_applicable, choice._w = b, applicable[steps - 1].copy(), weights[steps - 1].copy()
    choice._trial_weights, choice._trial_applicable = list(weights[:steps]), list(applicable[:steps + 1])
    agent.end_trial()
    agent.learn()
    return TrialStats(steps, total, bool(docked), not docked, {"success": bool(docked)})


def compiled_greedy(env, agent) -> bool:
    """Whether ``greedy_play`` plays Ch. 8's recurrent-Q test in ``env`` compiled (``recharge_play.compiled`` takes
    Ch. 6's learner)."""
    if type(agent) is not BehaviourRecurrentQ or type(agent.net) is not RecurrentOAON:
        return False
    c = agent.net.config
    return (c.n_outputs == 1 and agent.net.n_nets == len(BEHAVIOUR_TASKS) == agent.n_actions
            and type(agent.choice) is BehaviourChoice and not methods_replaced(agent) and compiled_world(env)
            and c.n_inputs == env.observation_space.shape[0])


def greedy_play(env, agent, seed: int, start) -> tuple[TrialStats, int]:
    """``run_trial(env, agent, trial=0, learning=False, seed=seed, options={"start": start})`` for Ch. 8's
    recurrent-Q where ``compiled_greedy(env, agent)``: the values at the context, the first best applicable behaviour
    (Eq. 6.6 at T = 0), the context moved on, the world's step. Returns its stats (their info holds "success" only)
    and the steps with a collision; the learner's record of the trial's choices is left as ``recharge_play``'s plays
    leave it (a test trial never reads it, the next trial begins it anew)."""
    obs, info = env.reset(seed=seed, options={"start": start})
    agent.begin_trial(obs, info, trial=0, learning=False)
    world, net = env.world, agent.net
    state = _state(obs, info, world)
    inputs, acted = np.empty((world.max_steps + 1, len(obs))), np.empty(len(BEHAVIOUR_TASKS), dtype=np.bool_)
    inputs[0] = agent._x
    q = np.empty(len(BEHAVIOUR_TASKS))
    steps, total, docked, hits, prim = _greedy_loop(net.play_arrays, library_arrays(env), _world(world), state,
                                                    inputs, world.sim.rng, q, acted)
    _, dk, dp, wf, pose, collision, trace = state
    leave(world, pose, collision, prim, steps, trace)
    env._task_obs = {"DK": dk, "DP": dp, "WFL": wf, "WFR": wf.copy()}
    agent._x, agent.last_q = inputs[steps - 1].copy(), q
    best = acted & (q == q[acted].max())
    agent.last_probabilities = best / best.sum()
    agent.end_trial()
    return TrialStats(steps, total, bool(docked), not docked, {"success": bool(docked)}), hits


@numba.njit(cache=False)
def _choice_weights(applicable, was, active, goal, persistence, persist, w):
    """``BehaviourChoice.weights``: W = applicability; with persistence ``persist`` for the behaviour followed
    (``active``, -1 at the trial's first step) unless it is inapplicable, reached its goal or another became
    applicable (``connrl.core.exploration.persistence_weights``)."""
    for k in range(w.size):
        w[k] = 1.0 if applicable[k] else 0.0
    if not persistence or active < 0 or not applicable[active] or goal:
        return
    for k in range(w.size):
        if applicable[k] and not was[k]:
            return
    w[active] = persist


@numba.njit(cache=False)
def _qcon_loop(net, learner, rule, lib, world, state, record, agent_rng, rng, q, p, qn, scratch):
    """Ch. 6's ``BehaviourQCON`` over the trial: its act and observe (Fig. 3.4 with Eq. 6.6's choice) around the
    world's step, until docked or the time limit. Returns (steps, total reward, docked, the last behaviour, its
    primitive), steps -1 where a choice met NaN values; ``q``: the last choice's values, ``p`` its distribution."""
    w1, w2, d1, d2 = net
    online, gamma, clip, has_clip, scale, lr, momentum, linear = learner
    persistence, persist, applicable_max, t = rule
    inputs, actions, rewards, weights, applicables = record
    scan = _scan_arrays(lib, state[1], state[2], state[3], w1.shape[1])
    applicable, h = scan[0], scan[4]
    was = np.zeros(applicable.size, dtype=np.bool_)
    pose, trace = state[4], state[6]
    steps, total, active, goal, max_steps = 0, 0.0, -1, False, world[-1]
    while True:
        x, y, w = inputs[steps], inputs[steps + 1], weights[steps]
        _values_any(w1, w2, x, h, scale, q, linear)
        _choice_weights(applicable, was, active, goal, persistence, persist, w)
        b = _weighted_choice(q, w, t, agent_rng, p, scratch)
        if b < 0:
            return -1, total, False, active, -1
        was[:] = applicable
        active = b
        prim, docked, reward, goal, _ = _behaviour_step(b, lib, world, state, rng, scan)
        steps += 1
        trace[steps, 0], trace[steps, 1], trace[steps, 2] = pose[0], pose[1], pose[2]
        _as_input(state[0], y)
        applicables[steps] = applicable
        actions[steps - 1], rewards[steps - 1] = b, reward
        total += reward
        if online:  # BehaviourChoice.next_value: the max over the applicable behaviours, when any is
            _online_q_step(w1, w2, d1, d2, b, x, y, docked, reward, gamma, clip, has_clip, h, qn, scale, lr, momentum,
                           linear, applicable, applicable_max and applicable.any())
        if docked or steps >= max_steps:
            return steps, total, docked, b, prim


@numba.njit(cache=False)
def _recurrent_loop(net, rule, lib, world, state, record, agent_rng, rng, q, p, scratch):
    """Ch. 8's ``BehaviourRecurrentQ`` over the trial: values at the context, Eq. 6.6's choice, the chosen net's
    hidden units as the next context (7.4), the world's step; no on-line learning (8.3). Returns as ``_qcon_loop``.
    ``net``: ``RecurrentOAON.play_arrays``."""
    w1, w2, scale, feedback, context, h_all, y = net
    persistence, persist, _, t = rule
    inputs, actions, rewards, weights, applicables = record
    scan = _scan_arrays(lib, state[1], state[2], state[3], 0)
    applicable = scan[0]
    was = np.zeros(applicable.size, dtype=np.bool_)
    pose, trace = state[4], state[6]
    steps, total, active, goal, max_steps = 0, 0.0, -1, False, world[-1]
    while True:
        w = weights[steps]
        _forward_all(w1, w2, inputs[steps], context, scale, h_all, y)
        for k in range(q.size):
            q[k] = y[k, 0]
        _choice_weights(applicable, was, active, goal, persistence, persist, w)
        b = _weighted_choice(q, w, t, agent_rng, p, scratch)
        if b < 0:
            return -1, total, False, active, -1
        for k in range(context.size):
            context[k] = feedback * h_all[b, k]
        was[:] = applicable
        active = b
        prim, docked, reward, goal, _ = _behaviour_step(b, lib, world, state, rng, scan)
        steps += 1
        trace[steps, 0], trace[steps, 1], trace[steps, 2] = pose[0], pose[1], pose[2]
        _as_input(state[0], inputs[steps])
        applicables[steps] = applicable
        actions[steps - 1], rewards[steps - 1] = b, reward
        total += reward
        if docked or steps >= max_steps:
            return steps, total, docked, b, prim


@numba.njit(cache=False)
def _greedy_loop(net, lib, world, state, inputs, rng, q, acted):
    """``greedy_play``'s trial: returns (steps, total reward, docked, collided steps, the last primitive); ``q`` and
    ``acted``: the last choice's values and the applicability it read; ``net``: ``RecurrentOAON.play_arrays``."""
    w1, w2, scale, feedback, context, h_all, y = net
    scan = _scan_arrays(lib, state[1], state[2], state[3], 0)
    applicable, pose, trace = scan[0], state[4], state[6]
    steps, total, hits, max_steps = 0, 0.0, 0, world[-1]
    while True:
        _forward_all(w1, w2, inputs[steps], context, scale, h_all, y)
        for k in range(q.size):
            q[k] = y[k, 0]
        b = _greedy_applicable(q, applicable, acted)
        for k in range(context.size):
            context[k] = feedback * h_all[b, k]
        prim, docked, reward, _, collided = _behaviour_step(b, lib, world, state, rng, scan)
        steps += 1
        trace[steps, 0], trace[steps, 1], trace[steps, 2] = pose[0], pose[1], pose[2]
        _as_input(state[0], inputs[steps])
        total += reward
        hits += collided
        if docked or steps >= max_steps:
            return steps, total, docked, hits, prim
