"""The deterministic grid worlds of 6.2: moves and walls, exact distances, regions and their centres by hand."""

import numpy as np
import pytest

from connrl.envs.grid import GridWorld


def test_moves_and_walls_on_a_3x3_grid():
    g = GridWorld(3, 2)  # state = 3 * row + col (axis 0 first); actions: +axis0, -axis0, +axis1, -axis1
    assert g.n == 9 and g.n_actions == 4
    assert g.next_state[4].tolist() == [7, 1, 5, 3]  # the middle moves everywhere
    assert g.next_state[0].tolist() == [3, 0, 1, 0]  # a corner: two moves hit walls and stay


def test_distances_are_manhattan_on_an_open_grid():
    g = GridWorld(6, 2)
    d = g.distances_to(g.index((1, 4)))
    manhattan = np.abs(g.coords - np.array([1, 4])).sum(axis=1)
    np.testing.assert_array_equal(d, manhattan)


def test_regions_and_centres_by_hand():
    g = GridWorld(7, 1)
    region, centres = g.regions(3)  # cells 0-2, 3-5, 6
    assert region.tolist() == [0, 0, 0, 1, 1, 1, 2] and centres.tolist() == [1, 4, 6]
    g2 = GridWorld(4, 2)
    _, c2 = g2.regions(2)  # four 2x2 blocks; the centre of each is its lower corner ((0 + 1) // 2 = 0)
    assert [tuple(g2.coords[c]) for c in c2] == [(0, 0), (0, 2), (2, 0), (2, 2)]
    with pytest.raises(ValueError, match="block must be"):
        g.regions(8)
    with pytest.raises(ValueError, match="side must be"):
        GridWorld(1)
