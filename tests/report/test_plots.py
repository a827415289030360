"""Learning-curve plots: runs on a common grid, PNG and SVG written atomically, redrawn from stored runs."""

import numpy as np
import pytest

from connrl.experiments import runner
from connrl.report.plots import curves_on_grid, plot_experiment, plot_from_disk
from tests.experiments.toy import spec


def test_curves_on_grid_by_hand():
    xs, ys = curves_on_grid([{"curve_x": [0, 2], "curve_y": [1.0, 3.0]}, {"curve_x": [0, 1, 2], "curve_y": [2, 4, 6]}])
    assert xs.tolist() == [0.0, 1.0, 2.0]
    np.testing.assert_array_equal(ys, [[1.0, np.nan, 3.0], [2.0, 4.0, 6.0]])


def test_plot_from_the_records_and_from_disk(tmp_path):
    with pytest.raises(FileNotFoundError, match="run `connrl run toy` first"):
        plot_from_disk(spec(), tmp_path)
    out = runner.run_experiment(spec(), profile="tiny", seed=2, out=tmp_path, workers=1, show_progress=False)
    assert not list((tmp_path / "toy").glob("curve.*"))  # the runner does not plot
    paths = plot_experiment(spec(), out.records, tmp_path / "toy")
    assert [p.name for p in paths] == ["curve.png", "curve.svg"]
    assert paths[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and b"<svg" in paths[1].read_bytes()[:400]
    paths[0].unlink()
    again = plot_from_disk(spec(), tmp_path)
    assert again == paths and all(p.exists() for p in again)
    assert not [p for p in (tmp_path / "toy").iterdir() if ".tmp" in p.name]  # written atomically
