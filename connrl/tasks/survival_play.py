"""Ch. 4's greedy test plays compiled whole (issue 45).

The protocol of 4.3.1 plays the 50 test environments greedily after every 20 training plays, and 4.3.4 plays 8000
more: test plays are most of Ch. 4's steps. With a rotated net (4.2.4) choosing, a test play -- the net's values at
the observation, the greedy choice, the world's step and its sensing -- runs as one Numba loop: the same arithmetic
and the same random draws, step for step, as ``run_trial(env, agent, learning=False)``, which
tests/tasks/test_survival_play.py holds it to. Any other agent, net or world plays through ``run_trial``.

The loop is not cached: it compiles in kernels of two other files, and a cached kernel may only call its own file's
(tests/nets/test_kernel_cache.py); it compiles once per process, in about a second.
"""

from __future__ import annotations

import numba
import numpy as np

from connrl.agents.ahcon import AHCON
from connrl.agents.qcon import QCON
from connrl.core.exploration import boltzmann_probabilities
from connrl.core.rollout import TrialStats, run_trial
from connrl.envs.survival.env import SurvivalEnv
from connrl.envs.survival.world import (
    _ENEMY_TABLE,
    _ENERGY_CODE,
    _FOOD_TABLE,
    _OBST_PAD,
    _OBST_TABLE,
    _TIMEOUT,
    _observe_kernel,
    _step_kernel,
)
from connrl.nets.kernels import _rotated_values
from connrl.nets.rotated import RotatedNet


def greedy_net(agent) -> RotatedNet | None:
    """The rotated net whose values a test play's greedy choice maximises (QCON's Q-net, AHCON's policy net), or
    None when the agent chooses some other way."""
    net = agent.q if type(agent) is QCON else agent.policy if type(agent) is AHCON else None
    return net if type(net) is RotatedNet else None


def greedy_play(env: SurvivalEnv, agent, seed: int) -> TrialStats:
    """``run_trial(env, agent, trial=0, learning=False, seed=seed, options={"layout_seed": seed})``, compiled when
    ``greedy_net(agent)`` gives a rotated net and ``env`` is a plain ``SurvivalEnv``."""
    net = greedy_net(agent)
    if net is None or type(env) is not SurvivalEnv:
        return run_trial(env, agent, trial=0, learning=False, seed=seed, options={"layout_seed": seed})
    obs, info = env.reset(seed=seed, options={"layout_seed": seed})
    agent.begin_trial(obs, info, trial=0, learning=False)
    o = net.net
    x = np.array(obs, dtype=np.float64)
    last_x, q = np.empty_like(x), np.empty(net.n_actions)
    steps, total, terminated = _greedy_loop(o.w1, o.w2, net.perms, o.scale, net._xr, q, last_x, x, world_of(env))
    env._done = True
    agent._x = last_x  # as act() leaves them: the input and the choice's distribution at the last step
    agent.last_probabilities = boltzmann_probabilities(q, 0.0)
    agent.end_trial()
    return TrialStats(steps, total, bool(terminated), not terminated, env._info())


def world_of(env: SurvivalEnv) -> tuple:
    """What ``_world_step`` reads and moves: the world's tables and arrays (moved in place), its generator, its time
    limit (-1: none) and local flag."""
    return (_OBST_PAD, env._food, env._enemy_count, env._enemies, env._agent, env._s, _FOOD_TABLE, _ENEMY_TABLE,
            _OBST_TABLE, _ENERGY_CODE, env.np_random, -1 if env.max_steps is None else env.max_steps, env._local)


@numba.njit(cache=False)
def _world_step(world, a, y):
    """``SurvivalEnv.step(a)`` on ``world_of(env)``, the observation written into ``y``: returns (reward,
    terminated, truncated)."""
    obst, food, enemy_count, enemies, agent, s, food_t, enemy_t, obst_t, energy_code, rng, max_steps, local = world
    direction = (s[1] + a) % 4 if local else a
    u = rng.random(2 * enemies.shape[0])
    reward = _step_kernel(obst, food, enemy_count, enemies, agent, s, direction, u)
    s[2] = a
    if local:
        s[1] = direction
    terminated = s[7] != 0
    truncated = not terminated and max_steps >= 0 and s[6] >= max_steps
    if truncated:
        s[7] = _TIMEOUT
    _observe_kernel(obst, food, enemy_count, agent, s, local, food_t, enemy_t, obst_t, energy_code, y)
    return reward, terminated, truncated


@numba.njit(cache=False)
def _greedy_loop(w1, w2, perms, scale, xr, q, last_x, x, world):
    """The play from observation ``x`` on: QCON's / AHCON's ``act(greedy=True)`` (the first of equal maxima; net 0
    when a value is NaN, as ``np.argmax`` of the NaN distribution gives) and ``SurvivalEnv.step`` until the play
    ends. Returns (steps, total reward, terminated); ``x`` ends as the last observation, ``last_x`` as the last
    input acted on, ``q`` as its values."""
    steps, total = 0, 0.0
    while True:
        _rotated_values(w1, w2, x, perms, scale, q, xr)
        a, best, nan = 0, q[0], False
        for k in range(q.size):
            nan = nan or np.isnan(q[k])
            if q[k] > best:
                a, best = k, q[k]
        if nan:
            a = 0
        last_x[:] = x
        reward, terminated, truncated = _world_step(world, a, x)
        steps += 1
        total += reward
        if terminated or truncated:
            return steps, total, terminated
