"""Robot rendering: frames, solution paths, the Fig. 5.3 panels."""

import numpy as np
import pytest

from connrl.envs.robot import (
    Layout,
    render_figure_5_3,
    render_frame,
    render_paths,
)
from tests.envs.robot_scenes import box_layout, exact_sim


def test_render_frame_and_paths(tmp_path):
    L = Layout.load("default")
    sim = exact_sim(L, L.locations["L3"])
    img = render_frame(L, sim.pose, reading=sim.sense(), rays=True, title="t")
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    f = tmp_path / "paths.png"
    img = render_paths(L, [[(300, 60, 90), (300, 72, 90)], [(60, 72), (70, 80)]], labels=["a", "b"], file=f)
    assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and img.shape[2] == 3
    with pytest.raises(ValueError, match="path 0"):
        render_paths(L, [[]])


def test_figure_5_3_panels(tmp_path):
    img = render_figure_5_3(file=tmp_path / "f.png", dpi=40)
    assert img.ndim == 3 and img.shape[2] == 3 and (tmp_path / "f.png").stat().st_size > 0
    np.testing.assert_array_equal(img, render_figure_5_3(dpi=40))  # same seed, same readings
    with pytest.raises(ValueError, match="no location 'L3'"):
        render_figure_5_3(box_layout(), dpi=40)
