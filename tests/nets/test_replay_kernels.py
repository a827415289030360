"""The compiled whole-lesson replays of ``connrl.nets.kernels``, called directly with their structured arguments
(a net's arrays, its settings, the replay's settings), against the plain loops they stand for: Fig. 5.1(a)
``connrl.core.replay.replay_q_reference``, Fig. 5.1(b) ``replay_ahc_reference`` and the recurrent net's batch replay
composed from ``batch_targets`` and ``train_sequence``. The wrappers of ``connrl.core.replay_kernel`` are tested in
tests/core; these hold the kernels themselves, beside them."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.agents.memory import replay_recurrent_q
from connrl.core.lessons import Lesson
from connrl.core.replay import REPAIRS, ReplayParams, replay_ahc_reference, replay_q_reference
from connrl.envs.survival import ACTION_ROTATION, ROTATION_PERMUTATIONS
from connrl.nets import OAON, NetConfig, RecurrentNetConfig, RecurrentOAON, kernels
from connrl.nets.rotated import RotatedNet
from tests.numpy_nets import NumpyOAON

NONE_F, NONE_B = np.zeros((0, 4)), np.zeros((0, 4), dtype=bool)


def _lessons(rng, n_lessons, d, binary=False):
    for k in range(n_lessons):
        n = int(rng.integers(1, 15))
        x = rng.choice([0.0, 1.0], (n + 1, d)) if binary else rng.uniform(-0.5, 1.0, (n + 1, d))
        yield Lesson(x, rng.integers(0, 4, n), rng.choice([0.0, -1.0, 0.4, 100.0], n), terminated=bool(k % 2))


def _same(a, b, names=("w1", "w2", "d1", "d2"), exact=True):
    for name in names:
        check = np.testing.assert_array_equal if exact else (lambda x, y: np.testing.assert_allclose(x, y, atol=1e-12))
        check(getattr(a, name), getattr(b, name))


@pytest.mark.parametrize("hidden, shared", [(5, False), (0, False), (5, True)])
@pytest.mark.parametrize("repair", REPAIRS)
@pytest.mark.parametrize("params", [ReplayParams(gamma=0.9, lam=0.7, temperature=10.0, p_threshold=0.2),
                                    ReplayParams(gamma=0.9, lam=0.0, clip=50.0),
                                    ReplayParams(gamma=0.95, lam=0.9, temperature=0.5, p_threshold=0.05, clip=60.0)])
def test_the_oaon_replay_is_the_plain_loop(hidden, shared, repair, params):
    """A net whose hidden layer every action shares (``shared_hidden``) against the plain loop on the independent
    NumPy net of tests/numpy_nets.py: after each update every action's value is new, which the kernel's reuse of the
    policy test's values must not miss."""
    cfg = NetConfig(7, hidden, value_range=100.0, init_range=0.5, lr=0.05, momentum=0.9 if hidden else 0.0,
                    shared_hidden=shared)
    fast = OAON(cfg, 4, np.random.default_rng(3))
    ref = NumpyOAON(fast) if shared else OAON(cfg, 4, np.random.default_rng(3))
    rng = np.random.default_rng(0)
    for lesson in _lessons(rng, 6, 7):
        n = len(lesson)
        weights = rng.choice([0.0, 1.0, 5.0], (n, 4)) if repair == "none" else None
        if weights is not None:
            weights[np.arange(n), lesson.actions] = 1.0
        allowed = rng.random((n + 1, 4)) < 0.6 if repair == "none" else None
        used = kernels._replay_q_kernel(fast.kernel_arrays, fast.kernel_settings, np.empty(4), lesson.inputs,
                                        lesson.actions, lesson.rewards, lesson.terminated, np.full(n, params.gamma),
                                        params.kernel_settings, REPAIRS.index(repair),
                                        NONE_F if weights is None else weights, NONE_B if allowed is None else allowed)
        assert used == replay_q_reference(ref, lesson, params, repair, weights, allowed)
        if shared:
            ref.assert_same(fast, tol=1e-10)
        else:
            _same(fast, ref, exact=False)  # fastmath: the nets agree to 1e-12


def test_the_oaon_replay_of_many_lessons_is_one_lesson_after_another():
    from connrl.core.lessons import pack_lessons

    cfg = NetConfig(7, 5, value_range=100.0, init_range=0.5, lr=0.05, momentum=0.9)
    many, one = (OAON(cfg, 4, np.random.default_rng(3)) for _ in range(2))
    lessons = list(_lessons(np.random.default_rng(1), 3, 7))
    order, thresholds = [2, 0, 2, 1], np.array([0.0, 0.2, 0.05, 0.3])
    params = ReplayParams(gamma=0.9, lam=0.7, temperature=10.0)
    pack = pack_lessons([lessons[i] for i in order], lambda lesson: (None, None), 4, lambda *a: None)
    used = kernels._replay_q_lessons(many.kernel_arrays, many.kernel_settings, np.empty(4), pack.inputs, pack.actions,
                                     pack.rewards, pack.terminated, np.full(int(pack.step_start[-1]), 0.9),
                                     pack.in_start, pack.step_start, pack.order, thresholds, params.kernel_settings,
                                     pack.weights, pack.allowed)
    want = 0
    for i, p_t in zip(order, thresholds, strict=True):
        at = ReplayParams(gamma=0.9, lam=0.7, temperature=10.0, p_threshold=float(p_t))
        want += kernels._replay_q_kernel(one.kernel_arrays, one.kernel_settings, np.empty(4), lessons[i].inputs,
                                         lessons[i].actions, lessons[i].rewards, lessons[i].terminated,
                                         np.full(len(lessons[i]), 0.9), at.kernel_settings, 0, NONE_F, NONE_B)
    assert used == want
    _same(many, one)


PARAMS = [ReplayParams(gamma=0.9, lam=0.0, temperature=0.05, p_threshold=0.01),
          ReplayParams(gamma=0.9, lam=0.7, temperature=0.5, p_threshold=0.3, clip=0.4),
          ReplayParams(gamma=0.9, lam=0.8)]


@pytest.mark.parametrize("params", PARAMS)
def test_the_rotated_replay_is_the_plain_loop_bit_for_bit(params):
    perms = ROTATION_PERMUTATIONS[list(ACTION_ROTATION)]
    cfg = NetConfig(perms.shape[1], 6, lr=0.3)
    fast, ref = (RotatedNet(cfg, perms, np.random.default_rng(4)) for _ in range(2))
    o = fast.net
    for lesson in _lessons(np.random.default_rng(9), 5, perms.shape[1], binary=True):
        used = kernels._replay_rotated_kernel(o.kernel_arrays, (o.scale, o.lr, cfg.momentum), fast._xr, np.empty(4),
                                              perms, lesson.inputs, lesson.actions, lesson.rewards,
                                              lesson.terminated, np.full(len(lesson), params.gamma),
                                              params.kernel_settings)
        assert used == replay_q_reference(ref, lesson, params)
        _same(fast.net, ref.net)


@pytest.mark.parametrize("params", PARAMS)
def test_the_ahc_replay_is_the_plain_loop_bit_for_bit(params):
    perms = ROTATION_PERMUTATIONS[list(ACTION_ROTATION)]
    n_in = perms.shape[1]
    (v, pol), ref = ((OAON(NetConfig(n_in, 5, lr=0.2), 1, np.random.default_rng(1)),
                      RotatedNet(NetConfig(n_in, 6, lr=0.3), perms, np.random.default_rng(4))) for _ in range(2))
    p = pol.net
    for lesson in _lessons(np.random.default_rng(9), 5, n_in, binary=True):
        used = kernels._replay_ahc_rotated_kernel(
            v.kernel_arrays, (v.scale, v.lr, v.config.momentum), p.kernel_arrays, (p.scale, p.lr, pol.config.momentum),
            pol._xr, np.empty(4), perms, lesson.inputs, lesson.actions, lesson.rewards, lesson.terminated,
            params.gamma, params.kernel_settings)
        assert used == replay_ahc_reference(*ref, lesson, params)
        _same(v, ref[0])
        _same(p, ref[1].net)


@pytest.mark.parametrize("params", [ReplayParams(gamma=0.9, lam=0.8, temperature=0.2, p_threshold=0.1, batch=True),
                                    ReplayParams(gamma=0.95, lam=0.0, clip=0.5, batch=True)])
def test_the_recurrent_replay_is_the_composed_batch_step_bit_for_bit(params):
    cfg = RecurrentNetConfig(4, 7, 3, 1, lr=0.3, momentum=0.9)
    fast, ref = (RecurrentOAON(cfg, 4, np.random.default_rng(3)) for _ in range(2))
    rng = np.random.default_rng(11)
    for lesson in _lessons(rng, 6, 4):
        n = len(lesson)
        w = rng.choice([0.0, 1.0, 100.0], (n, 4))
        w[np.arange(n), lesson.actions] = 1.0
        ok = rng.random((n + 1, 4)) < 0.6
        used = kernels._replay_recurrent_lesson(fast.kernel_arrays, fast.kernel_settings, lesson.inputs,
                                                lesson.actions, lesson.rewards, lesson.terminated, params.gamma,
                                                params.kernel_settings, w, ok)
        assert used == replay_recurrent_q(ref, lesson, params, w, ok, fast=False)
        _same(fast, ref)
