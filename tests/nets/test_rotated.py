"""The rotated single net of the global survival representation (4.2.4)."""

import numpy as np
import pytest

from connrl.envs.survival import ACTION_ROTATION, ROTATION_PERMUTATIONS, rotate_observation
from connrl.nets import OAON, NetConfig
from connrl.nets.rotated import RotatedNet

PERMS = np.stack([ROTATION_PERMUTATIONS[ACTION_ROTATION[a]] for a in range(4)])


def test_rotated_net_values_are_one_net_on_rotated_inputs():
    cfg = NetConfig(145, 6, lr=0.2, init_range=0.3)
    net = RotatedNet(cfg, PERMS, np.random.default_rng(0))
    ref = OAON(cfg, 1, np.random.default_rng(0))
    x = np.random.default_rng(1).choice([-0.5, 0.5], 145)
    for a in range(4):
        assert net.values(x)[a] == pytest.approx(ref.values(rotate_observation(x, a))[0], abs=1e-12)
        assert net.value(x, a) == pytest.approx(net.values(x)[a], abs=1e-12)
    # action symmetry: Q(rot(x, k), d) = Q(x, k + d)
    np.testing.assert_allclose(net.values(rotate_observation(x, 1)), np.roll(net.values(x), -1), atol=1e-12)
    ref_before = ref.update(rotate_observation(x, 2), 0, 0.9)
    assert net.update(x, 2, 0.9) == pytest.approx(ref_before, abs=1e-12)
    np.testing.assert_allclose(net.net.w1, ref.w1, atol=1e-12)
    with pytest.raises(ValueError, match="permutation"):
        RotatedNet(cfg, np.zeros((4, 145), dtype=int), np.random.default_rng(0))
