"""Ch. 7's cup-collection trials compiled whole (issue 45).

Each of the 500 trials of a cup run is a training trial and two greedy test episodes (7.5.1), each step a dozen
Python calls: the Q-values, the Boltzmann choice, recurrent-model's model or recurrent-Q's nets moving their context on
by the chosen action's net (7.4) or window-Q's window shifted, the corridor's step and its sensation (with Task 2's
random bits and Task 3's control errors drawn from the world's generator) and, in training, the on-line update of
recurrent-model's and window-Q's feed-forward Q-nets (Fig. 3.4). ``learning_play`` and ``test_score`` run them as one
Numba loop with the same arithmetic and the same draws from the learner's and the world's generators as
``run_trial`` and ``connrl.tasks.hidden_state.test_score``; the lesson, the model's training and the replays after a
trial are the Python path's own. tests/tasks/test_cup_play.py holds the two to each other, nets and streams bit for
bit.

Compiled: a plain ``CupCollectionEnv`` (under ``WastedPickUps`` for tests) and a ``RecurrentModelQ`` (its Q-net an
``OAON``), a ``RecurrentQ`` over ``RecurrentOAON`` nets or a ``WindowQ`` over an ``OAON`` without a planner,
exploring without stuck detection at a temperature above 0 (in training); anything else (another class or subclass,
a method replaced on the instance of the learner or its parts) plays through ``run_trial``. The returned stats' info
is empty. Not cached: the Boltzmann choice holds NumPy's ``exp``.
"""

from __future__ import annotations

import numba
import numpy as np

from connrl.agents.base import Exploration, methods_replaced
from connrl.agents.memory import RecurrentModelQ, RecurrentQ, SensationWindow, WindowQ, window_input_size
from connrl.core.boltzmann_kernel import _boltzmann_choice, _nanmax, compiled_choice_fits
from connrl.core.rollout import TrialStats, run_trial
from connrl.envs.cup import INSTANCES, N_CELLS, OFF, ON, CupCollectionEnv
from connrl.nets import OAON
from connrl.nets.kernels import _forward_all, _values_any
from connrl.nets.recurrent import RecurrentOAON
from connrl.tasks import hidden_state
from connrl.tasks.robot_train import NOT_RESTRICTED, _online_q_step

LEFT, RIGHT, PICK_UP = 0, 1, 2


def compiled(env, agent) -> bool:
    """Whether the loops play ``agent`` in ``env`` (the module docstring's cases), every shape they index checked."""
    world = env.env if type(env) is hidden_state.WastedPickUps else env
    if type(world) is not CupCollectionEnv or world.render_mode is not None or methods_replaced(agent):
        return False
    n_s, n_a = world.observation_space.shape[0], agent.n_actions
    if type(agent) is RecurrentModelQ:
        model, q = agent.model, agent.q
        nets = (type(model) is RecurrentOAON and type(q) is OAON and q.n_nets == n_a and model.n_nets == n_a
                and model.config.n_inputs == n_s and q.config.n_inputs == n_s + model.config.n_context
                and agent.config.target_clip is None)
    elif type(agent) is RecurrentQ:
        net = agent.net
        nets = (type(net) is RecurrentOAON and net.config.n_outputs == 1 and net.n_nets == n_a
                and net.config.n_inputs == n_s)
    elif type(agent) is WindowQ:
        m, q = agent.memory, agent.q
        nets = (type(m) is SensationWindow and type(q) is OAON and agent.planner is None and q.n_nets == n_a
                and (m.n_sensation, m.n_actions) == (n_s, n_a) and q.config.n_inputs == window_input_size(
                    n_s, n_a, m.window) and m.sensations.shape == (m.window, n_s)
                and m.actions.shape == (m.window, n_a))
    else:
        return False
    return (nets and n_a == 3 and type(agent.explore) is Exploration and agent.explore.detector is None
            and compiled_choice_fits(n_a))


def learning_play(env: CupCollectionEnv, agent, *, trial: int) -> TrialStats:
    """``run_trial(env, agent, trial=trial, learning=True)``, compiled where ``compiled(env, agent)`` and the trial's
    temperature is above 0 and the recorder empty."""
    if not (compiled(env, agent) and agent.explore.schedule(trial) > 0 and agent.book.recorder.empty()):
        return run_trial(env, agent, trial=trial, learning=True)
    obs, info = env.reset()
    agent.begin_trial(obs, info, trial=trial, learning=True)
    steps, total, terminated, inputs, actions, rewards, p = _play(env, agent, obs, True)
    agent.took_compiled_trial(inputs[:steps + 1], actions[:steps], rewards[:steps], terminated, p)
    if type(agent) is not WindowQ:  # the input of the last choice: their observe keeps no next one
        agent._x = inputs[steps - 1].copy()
    agent.end_trial()
    agent.learn()
    return TrialStats(steps, total, terminated, not terminated, {})


def test_score(env, agent) -> int:
    """``connrl.tasks.hidden_state.test_score``: one greedy episode per instance, the steps summed; compiled where
    ``compiled(env, agent)``."""
    if not compiled(env, agent):
        return hidden_state.test_score(env, agent)
    score = 0
    for instance in INSTANCES:
        obs, info = env.reset(options={"instance": instance})
        agent.begin_trial(obs, info, trial=0, learning=False)
        steps, _, _, inputs, _, _, p = _play(env, agent, obs, False)
        agent._x, agent.last_probabilities = inputs[steps - 1].copy(), p
        agent.end_trial()
        score += steps
    return score


def _play(env, agent, obs, learning: bool):
    """One trial from ``obs`` on, the world and learner left as ``run_trial`` leaves them but for the lesson:
    (steps, total reward, terminated, inputs, actions, rewards, the last choice's distribution)."""
    world = env.env if type(env) is hidden_state.WastedPickUps else env
    cap = world.max_steps - world._steps
    window = type(agent) is WindowQ
    width = agent.q.config.n_inputs if window else len(obs)
    inputs, actions, rewards = np.empty((cap + 1, width)), np.empty(cap, np.int64), np.empty(cap)
    inputs[0] = agent._x if window else obs
    cups = np.zeros(N_CELLS, dtype=np.bool_)
    cups[list(world.cups)] = True
    cell = np.array([world.position, world._collision, world._steps, 0], dtype=np.int64)
    spec = (world.random_bits, world.control_error, world.max_steps)
    t = 0.0 if not learning else agent.explore.base * agent.merit_scale
    p, q, scratch = np.empty(agent.n_actions), np.empty(agent.n_actions), np.zeros(5, np.int64)
    record = (inputs, actions, rewards)
    if type(agent) is RecurrentModelQ:
        qn, m = agent.q, agent.model
        qnet = (qn.w1, qn.w2, qn.d1, qn.d2, qn.scale, qn.lr, qn.config.momentum, qn.config.linear_output)
        agent._xq = np.empty(len(obs) + m.config.n_context)  # the last choice's Q-net input
        learner = (learning and agent.config.online, agent.config.gamma, t)
        steps, total, terminated = _model_loop(qnet, m.play_arrays, learner, spec, cups, cell, record, agent.rng,
                                               world.np_random, q, p, scratch, agent._xq)
    elif window:
        qn, now, last, last_obs = agent.q, np.array(obs, dtype=np.float64), np.array([-1]), np.empty(len(obs))
        qnet = (qn.w1, qn.w2, qn.d1, qn.d2, qn.scale, qn.lr, qn.config.momentum, qn.config.linear_output)
        c = agent.config
        learner = (learning, learning and c.online, c.gamma, 0.0 if c.target_clip is None else c.target_clip,
                   c.target_clip is not None, t)
        steps, total, terminated = _window_loop(qnet, learner, agent.memory.sensations, agent.memory.actions, spec,
                                                cups, cell, record, now, (last, last_obs), agent.rng,
                                                world.np_random, q, p, scratch)
        agent._last_obs, agent._last_action = last_obs, None if last[0] < 0 else int(last[0])
    else:
        steps, total, terminated = _recurrent_loop(agent.net.play_arrays, t, spec, cups, cell, record, agent.rng,
                                                   world.np_random, q, p, scratch)
    world.position, world._collision, world._steps = int(cell[0]), int(cell[1]), int(cell[2])
    world.cups, world._done = frozenset(np.flatnonzero(cups).tolist()), True
    if world is not env:
        env.wasted += int(cell[3])
    agent.last_probabilities = p
    return steps, total, terminated, inputs, actions, rewards, p


@numba.njit(cache=False)
def _cup_step(spec, cups, cell, a, rng, y):
    """``CupCollectionEnv.step(a)`` after its checks (``cell``: position, collision, steps, and pick-ups that collect
    nothing, ``WastedPickUps``'s count): the new sensation into ``y``. Returns (reward, terminated, truncated)."""
    random_bits, control_error, max_steps = spec
    reward, pos = 0.0, cell[0]
    if control_error > 0.0 and rng.random() < control_error:
        cell[1] = 0  # a failed action has no effect at all (7.5.3)
        cell[3] += a == PICK_UP
    elif a == LEFT:
        cell[0], cell[1] = (pos - 1, 0) if pos > 0 else (pos, -1)
    elif a == RIGHT:
        cell[0], cell[1] = (pos + 1, 0) if pos < N_CELLS - 1 else (pos, 1)
    else:
        cell[1] = 0
        if cups[pos]:
            cups[pos] = False
            reward = 0.0 if cups.any() else 1.0
        else:
            cell[3] += 1
    cell[2] += 1
    terminated = not cups.any()
    pos = cell[0]
    y[0] = ON if pos >= 1 and cups[pos - 1] else OFF
    y[1] = ON if pos + 1 < N_CELLS and cups[pos + 1] else OFF
    y[2] = ON if cell[1] < 0 else OFF
    y[3] = ON if cell[1] > 0 else OFF
    for k in range(random_bits):  # np.where(random(k) < 0.5, OFF, ON): the draws in order
        y[4 + k] = OFF if rng.random() < 0.5 else ON
    return reward, terminated, not terminated and cell[2] >= max_steps


@numba.njit(cache=False)
def _choose(q, t, agent_rng, p, scratch):
    """``boltzmann_select(q, t, rng)``: the draw for t > 0; at t = 0 the first best, p shared among the best (all NaN
    and action 0 for NaN values, as ``boltzmann_probabilities`` and ``np.argmax`` give)."""
    if t > 0:
        return _boltzmann_choice(q, t, agent_rng, p, scratch)
    top, best = _nanmax(q, q.size), 0.0
    for k in range(q.size):
        p[k] = 1.0 if q[k] == top else 0.0
        best += p[k]
    a = -1
    for k in range(q.size):
        p[k] /= best
        if a < 0 and (p[k] != p[k] or p[k] > 0):
            a = k
    return max(a, 0)


@numba.njit(cache=False)
def _move_on(a, feedback, h_all, context, spec, cups, cell, rng, record, steps):
    """After choice ``a`` of step ``steps``: the context from net a's hidden units (7.4), the world's step, the
    experience recorded. Returns ``_cup_step``'s (reward, terminated, truncated)."""
    inputs, actions, rewards = record
    for k in range(context.size):
        context[k] = feedback * h_all[a, k]
    reward, terminated, truncated = _cup_step(spec, cups, cell, a, rng, inputs[steps + 1])
    actions[steps], rewards[steps] = a, reward
    return reward, terminated, truncated


@numba.njit(cache=False)
def _model_loop(qnet, model, learner, spec, cups, cell, record, agent_rng, rng, q, p, scratch, xq):
    """Recurrent-model over the trial: the Q-values on [sensation, context], the choice, the model told the action
    (its context moved on), the world's step, and with ``online`` Fig. 3.4's update on the step. Returns (steps,
    total reward, terminated); the experiences are left in ``record``, the last choice's input in ``xq``."""
    qw1, qw2, qd1, qd2, qscale, qlr, qmomentum, qlinear = qnet
    mw1, mw2, mscale, feedback, context, h_all, y = model
    online, gamma, t = learner
    inputs = record[0]
    n_s = inputs.shape[1]
    h, yq, qn = np.empty(max(qw1.shape[1], 1)), np.empty(xq.size), np.empty(q.size)
    steps, total = 0, 0.0
    while True:
        x = inputs[steps]
        xq[:n_s], xq[n_s:] = x, context
        _values_any(qw1, qw2, xq, h, qscale, q, qlinear)
        a = _choose(q, t, agent_rng, p, scratch)
        _forward_all(mw1, mw2, x, context, mscale, h_all, y)
        reward, terminated, truncated = _move_on(a, feedback, h_all, context, spec, cups, cell, rng, record, steps)
        steps += 1
        total += reward
        if online:  # on [y, the context moved on]; no clip (compiled() takes target_clip None only)
            yq[:n_s], yq[n_s:] = inputs[steps], context
            _online_q_step(qw1, qw2, qd1, qd2, a, xq, yq, terminated, reward, gamma, 0.0, False, h, qn, qscale, qlr,
                           qmomentum, qlinear, NOT_RESTRICTED, False)
        if terminated or truncated:
            return steps, total, terminated


@numba.njit(cache=False)
def _recurrent_loop(net, t, spec, cups, cell, record, agent_rng, rng, q, p, scratch):
    """Recurrent-Q over the trial: the values at the context, the choice, the chosen net's hidden units as the next
    context (7.4), the world's step; no on-line learning (7.5). Returns as ``_model_loop``."""
    w1, w2, scale, feedback, context, h_all, y = net
    inputs = record[0]
    steps, total = 0, 0.0
    while True:
        _forward_all(w1, w2, inputs[steps], context, scale, h_all, y)
        for k in range(q.size):
            q[k] = y[k, 0]
        a = _choose(q, t, agent_rng, p, scratch)
        reward, terminated, truncated = _move_on(a, feedback, h_all, context, spec, cups, cell, rng, record, steps)
        steps += 1
        total += reward
        if terminated or truncated:
            return steps, total, terminated


@numba.njit(cache=False)
def _push(sens, acts, s, a):
    """``SensationWindow.push(s, a)``: the window shifted one slot older, ``s`` and action ``a`` (one-hot in +-0.5)
    in front."""
    for i in range(sens.shape[0] - 1, 0, -1):
        sens[i, :] = sens[i - 1, :]
        acts[i, :] = acts[i - 1, :]
    sens[0, :] = s
    acts[0, :] = OFF
    acts[0, a] = ON


@numba.njit(cache=False)
def _encode(s, sens, acts, x):
    """``SensationWindow.encode(s)`` into ``x``: [s, the window's sensations, its actions]."""
    k = 0
    for v in (s, sens.ravel(), acts.ravel()):
        for j in range(v.size):
            x[k] = v[j]
            k += 1


@numba.njit(cache=False)
def _window_loop(qnet, learner, sens, acts, spec, cups, cell, record, now, last, agent_rng, rng, q, p, scratch):
    """Window-Q over the trial (``WindowQ.act`` and, learning, ``observe``): the values on the encoded window, the
    choice, the world's step, the window shifted and, with ``online``, Fig. 3.4's update. A test play shifts the
    window and encodes at each choice, as ``act`` does without ``observe``. ``now``: the current sensation;
    ``last``: (the action not yet in the window, -1 for none; the sensation of the last choice). Returns as
    ``_model_loop``."""
    w1, w2, d1, d2, scale, lr, momentum, linear = qnet
    learning, online, gamma, clip, has_clip, t = learner
    inputs, actions, rewards = record
    pending, last_obs = last
    h, qn, s_next = np.empty(max(w1.shape[1], 1)), np.empty(q.size), np.empty(now.size)
    steps, total = 0, 0.0
    while True:
        x = inputs[steps]
        if not learning:
            if pending[0] >= 0:
                _push(sens, acts, last_obs, pending[0])
            _encode(now, sens, acts, x)
        _values_any(w1, w2, x, h, scale, q, linear)
        a = _choose(q, t, agent_rng, p, scratch)
        last_obs[:] = now
        pending[0] = a
        reward, terminated, truncated = _cup_step(spec, cups, cell, a, rng, s_next)
        steps += 1
        actions[steps - 1], rewards[steps - 1] = a, reward
        total += reward
        now[:] = s_next
        if learning:
            _push(sens, acts, last_obs, a)
            pending[0] = -1
            _encode(now, sens, acts, inputs[steps])
            if online:
                _online_q_step(w1, w2, d1, d2, a, x, inputs[steps], terminated, reward, gamma, clip, has_clip, h, qn,
                               scale, lr, momentum, linear, NOT_RESTRICTED, False)
        if terminated or truncated:
            return steps, total, terminated
