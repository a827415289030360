"""Ch. 4's compiled lesson replays (issue 45): a rotated Q-net's (Fig. 5.1a) and AHCON's (Fig. 5.1b), each the
registered fast path of its plain loop, held to that loop bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from connrl.core import replay as replay_module
from connrl.core.lessons import Lesson
from connrl.core.replay import ReplayParams, replay_ahc, replay_q, replay_q_reference
from connrl.nets import OAON, NetConfig


@pytest.mark.parametrize("terminated", [True, False])
@pytest.mark.parametrize("params", [
    ReplayParams(gamma=0.9, lam=0.0, temperature=0.05, p_threshold=0.01),  # Ch. 4's QCON-R
    ReplayParams(gamma=0.9, lam=0.7, temperature=0.5, p_threshold=0.3, clip=0.4),  # many cut, targets truncated
    ReplayParams(gamma=0.95, lam=0.5, temperature=0.0, p_threshold=0.6),  # greedy, ties shared
    ReplayParams(gamma=0.9, lam=0.8),  # every experience replayed
])
def test_the_rotated_nets_compiled_replay_is_the_reference_loop_bit_for_bit(terminated, params):
    """Ch. 4's nets (one net on rotated inputs, 4.2.4): the registered fast path against the plain loop, exactly,
    over lessons in a row (momentum carries), including the non-policy test and the TD arithmetic."""
    from connrl.envs.survival import ACTION_ROTATION, ROTATION_PERMUTATIONS
    from connrl.nets.rotated import RotatedNet

    perms = ROTATION_PERMUTATIONS[list(ACTION_ROTATION)]
    cfg = NetConfig(perms.shape[1], 6, lr=0.3)
    fast, ref = (RotatedNet(cfg, perms, np.random.default_rng(4)) for _ in range(2))
    if params.temperature == 0:  # a net with no weights gives every rotation the same value: all four tie
        for net in (fast, ref):
            net.net.w1[...] = 0.0
    rng = np.random.default_rng(9)
    used = steps = 0
    for k in range(5):
        n = int(rng.integers(1, 15))
        lesson = Lesson(rng.choice([0.0, 1.0], (n + 1, perms.shape[1])), rng.integers(0, 4, n),
                        rng.choice([0.0, 0.0, 0.4, -1.0], n), terminated if k else True)
        assert replay_q(fast, lesson, params) == (u := replay_q_reference(ref, lesson, params))
        used, steps = used + u, steps + n
        for name in ("w1", "w2", "d1", "d2"):
            np.testing.assert_array_equal(getattr(fast.net, name), getattr(ref.net, name))
    assert used == steps if params.p_threshold == 0 else used <= steps
    assert used < steps or params.p_threshold < 0.3  # the high thresholds cut some experiences
    assert replay_module.FAST_PATHS[RotatedNet].__name__ == "replay_rotated"


@pytest.mark.parametrize("params", [
    ReplayParams(gamma=0.9, lam=0.0, temperature=0.05, p_threshold=0.01),  # Ch. 4's AHCON-R
    ReplayParams(gamma=0.9, lam=0.7, temperature=0.5, p_threshold=0.3, clip=0.4),
    ReplayParams(gamma=0.95, lam=0.5, temperature=0.0, p_threshold=0.6),
    ReplayParams(gamma=0.9, lam=0.8),
])
def test_ahcons_compiled_replay_is_the_reference_loop_bit_for_bit(params):
    """Ch. 4's AHCON nets (a V-net, a rotated policy net): Fig. 5.1(b)'s registered fast path against the plain loop,
    exactly, over lessons in a row."""
    from connrl.core.replay import AHC_FAST_PATHS, replay_ahc_reference
    from connrl.envs.survival import ACTION_ROTATION, ROTATION_PERMUTATIONS
    from connrl.nets.rotated import RotatedNet

    perms = ROTATION_PERMUTATIONS[list(ACTION_ROTATION)]
    n_in = perms.shape[1]
    fast, ref = ((OAON(NetConfig(n_in, 5, lr=0.2), 1, np.random.default_rng(1)),
                  RotatedNet(NetConfig(n_in, 6, lr=0.3), perms, np.random.default_rng(4))) for _ in range(2))
    if params.temperature == 0:
        for _, pol in (fast, ref):
            pol.net.w1[...] = 0.0  # every rotation ties
    rng = np.random.default_rng(9)
    used = steps = 0
    for k in range(5):
        n = int(rng.integers(1, 15))
        lesson = Lesson(rng.choice([0.0, 1.0], (n + 1, n_in)), rng.integers(0, 4, n),
                        rng.choice([0.0, 0.0, 0.4, -1.0], n), bool(k % 2))
        assert replay_ahc(*fast, lesson, params) == (u := replay_ahc_reference(*ref, lesson, params))
        used, steps = used + u, steps + n
        for a, b in ((fast[0], ref[0]), (fast[1].net, ref[1].net)):
            for name in ("w1", "w2", "d1", "d2"):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert used == steps if params.p_threshold == 0 else used <= steps
    assert used < steps or params.p_threshold < 0.3
    assert AHC_FAST_PATHS[(OAON, RotatedNet)].__name__ == "replay_ahc_rotated"
