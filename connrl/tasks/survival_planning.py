"""Relaxation planning of Ch. 4's -M agents inside the compiled training play (issue 45).

``connrl.core.planning.RelaxationPlanner.plan`` with the survival models of ``connrl.tasks.survival_models``, as
kernels that ``connrl.tasks.survival_train``'s loop calls before each choice, and the learned model's on-line
training after each step. Same arithmetic and draws as the Python path, bit for bit:

* the promising actions from Eq. 3.4's probabilities, NumPy's ``exp`` (``connrl.core.boltzmann_kernel``);
* the perfect model's step: the scratch world set to the live one, then stepped with the scratch world's generator,
  once per promising action (``PerfectSurvivalModel.steps_from``);
* the learned model's prediction and training (``_predict``, ``_train_row``) and its replay draws from the agent's
  generator, whose ``integers`` Numba computes as NumPy does (checked by the tests);
* AHCON's ``mu``, sum p E / sum p, as the same plain loops of products and sums (``relaxation_ahc``);
* the learned model's squared error ``reward_abs ** 2``: Python's ``**`` is libm's ``pow``, which for about one number
  in a thousand is not ``x * x`` (what Numba makes of it), so the kernel keeps each step's ``reward_abs`` and
  ``leave_planning`` squares and sums them in Python, in the same order.

Not cached: it compiles in kernels of other files (tests/nets/test_kernel_cache.py).
"""

from __future__ import annotations

import numba
import numpy as np

from connrl.core.boltzmann_kernel import _nanmax, _probabilities
from connrl.core.planning import RelaxationPlanner
from connrl.envs.survival.world import N_INPUTS
from connrl.nets.kernels import _forward_at, _mlp_update, _mlp_values, _rotated_update, _rotated_values
from connrl.tasks.survival_models import (
    LearnedSurvivalModel,
    PerfectSurvivalModel,
    _predict,
    _train_row,
    _wrong_share,
)
from connrl.tasks.survival_play import _world_step, world_of


def plan_fits(agent, env) -> bool:
    """Whether the loop plans as ``agent.planner`` would: no planner, or a relaxation planner whose survival model
    simulates this very world (and, learning, draws from the agent's generator), for at most four actions."""
    planner = agent.planner
    if planner is None:
        return True
    if type(planner) is not RelaxationPlanner or agent.n_actions > 4:
        return False
    model = planner.model
    if type(model) is PerfectSurvivalModel:
        return model.env is env
    return (type(model) is LearnedSurvivalModel and type(model.sim) is PerfectSurvivalModel and model.sim.env is env
            and model.rng is agent.rng)


def planning_of(agent, env, trial: int, cap: int) -> tuple:
    """What the loop reads and moves of ``agent.planner`` (dummies without one): (whether to plan in this play, the
    promising threshold, whether the model learns, the scratch world, the learned model, counters, errors, each of
    the play's at most ``cap`` reward errors)."""
    planner = agent.planner
    counters = np.zeros(4, np.int64)  # planner.steps, planner.hypothetical, model._n, model.errors["n"]
    errors = np.zeros(3)  # model.errors' reward_abs, (unused), enemy_bits
    if planner is None:
        return (False, 0.0, False, world_of(env), _no_model(), counters, errors, np.empty(1))
    model = planner.model
    learned = type(model) is LearnedSurvivalModel
    counters[:2] = planner.steps, planner.hypothetical
    m = _no_model()
    if learned:
        c = model.config
        counters[2:] = model._n, model.errors["n"]
        errors[:] = model.errors["reward_abs"], 0.0, model.errors["enemy_bits"]
        m = (model.w_r, model.w_e, model.d_r, model.d_e, model.perms, model._q, model._xr, model._yr, model._out_r,
             model._out_e, float(c.lr), float(c.momentum), float(c.death_threshold), int(c.replays),
             bool(model.global_), (0, *model.MAPS))
    scratch = (model.sim if learned else model).scratch
    return (trial >= planner.config.start_trial, float(planner.config.promising), learned, world_of(scratch), m,
            counters, errors, np.empty(cap if learned else 1))


def leave_planning(agent, planning) -> None:
    """Write the loop's counters and errors back into the planner and its model."""
    planner = agent.planner
    if planner is None:
        return
    counters, errors = planning[5], planning[6]
    planner.steps, planner.hypothetical = int(counters[0]), int(counters[1])
    if planning[2]:
        model = planner.model
        reward_sq = model.errors["reward_sq"]
        for v in planning[7][:int(counters[3]) - model.errors["n"]].tolist():
            reward_sq += v ** 2  # as LearnedSurvivalModel.learn squares: libm's pow, not Numba's v * v
        model._n = int(counters[2])
        model.errors.update(reward_abs=float(errors[0]), reward_sq=reward_sq, enemy_bits=float(errors[2]),
                            n=int(counters[3]))


def _no_model() -> tuple:
    z3, z2 = np.zeros((1, 1, 1)), np.zeros((1, 1))
    return (z3, z3, z3, z3, np.zeros((1, 1), np.int64), z2, np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1),
            0.0, 0.0, 0.0, 0, True, (0, 0, 0))


def plan_buffers(n_actions: int) -> tuple:
    """Scratch of the planning kernels: outcomes, rewards, terminals, actions, targets, probabilities, enemy units,
    a model's row, NumPy's exp loop's arguments."""
    return (np.empty((n_actions, N_INPUTS)), np.empty(n_actions), np.zeros(n_actions, np.bool_),
            np.empty(n_actions, np.int64), np.empty(n_actions), np.empty(n_actions), np.empty(32),
            np.empty(2 * N_INPUTS + 2), np.zeros(5, np.int64))


# ------------------------------------------------------------------------------------------------ the nets

@numba.njit(cache=False)
def _values(net, x, q):
    """``net.values(x)`` into q; ``net`` as ``connrl.tasks.survival_train._net_of`` gives it."""
    w1, w2, d1, d2, h, xr, perms, scale, lr, momentum, rotated = net
    if rotated:
        _rotated_values(w1, w2, x, perms, scale, q, xr)
    else:
        _mlp_values(w1, w2, x, h, scale, q)


@numba.njit(cache=False)
def _update(net, x, a, value, is_error):
    """``net.update(x, a, value)`` (``update_error`` when ``is_error``); returns the output before the step."""
    w1, w2, d1, d2, h, xr, perms, scale, lr, momentum, rotated = net
    if rotated:
        return _rotated_update(w1, w2, d1, d2, x, perms[a], xr, h, value, is_error, scale, lr, momentum)
    return _mlp_update(w1, w2, d1, d2, a, x, h, value, is_error, scale, lr, momentum)


@numba.njit(cache=False)
def _value(v, x):
    """AHCON's ``v.value(x, 0)`` (``_forward_at`` itself, as the kernels call it: not through ``_mlp_forward``)."""
    return v[7] * _forward_at(v[0], v[1], 0, x, 0, v[4])


# -------------------------------------------------------------------------------------------- the planning

@numba.njit(cache=False)
def _plan(net, v, ahcon, x, q, t, gamma, clip, has_clip, world, planning, bufs):
    """``RelaxationPlanner.plan(agent, x, q, t)`` for QCON (``ahcon`` False, Fig. 3.6) or AHCON (Fig. 3.5, ``q`` the
    policy's merits); True when the nets were changed. ``q`` is scratch afterwards."""
    ys, rs, terms, actions, targets, p, enemy, row, scratch = bufs
    planning[5][0] += 1
    if not planning[0]:
        return False
    _probabilities(q, q[:0], t, p, scratch)
    n = 0
    for k in range(q.size):  # step 3: the promising actions
        if p[k] > planning[1]:
            actions[n] = k
            n += 1
    if n < 2:
        return False
    _simulate(x, n, world, planning, bufs)
    planning[5][1] += n
    for i in range(n):  # step 4: U'_a (Q) or E_a (AHC), truncated at the clip
        if terms[i]:
            u = 0.0
        elif ahcon:
            u = _value(v, ys[i])
        else:
            _values(net, ys[i], q)
            u = _nanmax(q, q.size)
        r = rs[i] + gamma * u
        targets[i] = r if not has_clip or r <= clip else clip
    if not ahcon:
        for i in range(n):
            _update(net, x, actions[i], targets[i], False)
        return True
    dot, mass = 0.0, 0.0
    for i in range(n):  # sum p E / sum p over S: relaxation_ahc's plain loops
        dot += p[actions[i]] * targets[i]
    for i in range(n):
        mass += p[actions[i]]
    mu = dot / mass
    _update(v, x, 0, _nanmax(targets, n), False)  # step 6
    for i in range(n):  # step 7
        _update(net, x, actions[i], targets[i] - mu, True)
    return True


@numba.njit(cache=False)
def _simulate(x, n, world, planning, bufs):
    """The model's outcomes of the first ``n`` promising actions into ``bufs`` (``PerfectSurvivalModel.simulate``;
    ``LearnedSurvivalModel.simulate`` with the learned enemy units and reinforcement)."""
    ys, rs, terms, actions, targets, p, enemy, row, scratch_args = bufs
    learned, scratch = planning[2], planning[3]
    w_r, w_e, d_r, d_e, perms, queue, xr, yr, out_r, out_e, lr, momentum, death, replays, global_, at = planning[4]
    start, lo, hi = at  # run-time values, as Python passes them: as constants LLVM would sum in another order
    for k in range(n):
        # the scratch world set to the live one (set_state, then _restore before each further action)
        scratch[1][:, :] = world[1]
        scratch[2][:, :] = world[2]
        scratch[3][:, :] = world[3]
        scratch[4][:] = world[4]
        scratch[5][:] = world[5]
        a = actions[k]
        r, terminated, _ = _world_step(scratch, a, ys[k])
        if learned:
            j = 0 if global_ else a
            r = _predict(w_r[j], w_e[j], x, perms[a], start, lo, hi, xr, out_r, out_e, enemy)
            for i in range(32):
                ys[k, 52 + i] = enemy[i]
            terminated = r < death or scratch[5][7] == 1  # 1: the play's outcome "all_food"
        rs[k], terms[k] = r, terminated


@numba.njit(cache=False)
def _model_learn(x, a, r, y, planning, rng, bufs, first):
    """``LearnedSurvivalModel.learn(x, a, r, y, terminated)``: the prediction errors before, one step on the new
    experience, then on ``replays`` queued ones drawn from ``rng``. The reward error goes to ``planning[7]``, at its
    count less ``first`` (the count when the play began), to be squared in Python."""
    w_r, w_e, d_r, d_e, perms, queue, xr, yr, out_r, out_e, lr, momentum, death, replays, global_, at = planning[4]
    start, lo, hi = at  # run-time values, as Python passes them: as constants LLVM would sum in another order
    counters, errors, enemy, row = planning[5], planning[6], bufs[6], bufs[7]
    play_errors = planning[7]
    n_in = x.size
    row[:n_in] = x
    row[n_in:2 * n_in] = y
    row[-2], row[-1] = a, r
    j = 0 if global_ else a
    pr = _predict(w_r[j], w_e[j], x, perms[a], start, lo, hi, xr, out_r, out_e, enemy)
    reward_abs = abs(pr - r)
    play_errors[counters[3] - first] = reward_abs
    errors[0] += reward_abs
    errors[2] += _wrong_share(enemy, y[52:84])
    counters[3] += 1
    _train_row(w_r[j], d_r[j], w_e[j], d_e[j], row, perms[a], start, lo, hi, lr, momentum, xr, yr, out_r, out_e)
    cap = queue.shape[0]
    queue[counters[2] % cap] = row
    counters[2] += 1
    for i in rng.integers(0, min(counters[2], cap), size=replays):
        b = int(queue[i, -2])
        j = 0 if global_ else b
        _train_row(w_r[j], d_r[j], w_e[j], d_e[j], queue[i], perms[b], start, lo, hi, lr, momentum, xr, yr, out_r,
                   out_e)
