"""Learning-curve plots (mean and spread over runs), PNG and SVG, with the thesis's reference lines."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from connrl.experiments.runner import missing_runs, stored_runs  # noqa: E402
from connrl.experiments.spec import ExperimentSpec  # noqa: E402
from connrl.storage import atomic_write_bytes  # noqa: E402


def curves_on_grid(records: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """Stack the runs' curves on the union of their x values (NaN where a run has no point)."""
    xs = np.unique(np.concatenate([np.asarray(r["curve_x"], dtype=float) for r in records] or [np.zeros(0)]))
    ys = np.full((len(records), xs.size), np.nan)
    for i, r in enumerate(records):
        idx = np.searchsorted(xs, np.asarray(r["curve_x"], dtype=float))
        ys[i, idx] = r["curve_y"]
    return xs, ys


def save_figure(fig, file: Path) -> Path:
    """Write ``fig`` to ``file`` (format from its suffix) atomically: a reader never sees half a plot."""
    file.parent.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    fig.savefig(buf, format=file.suffix[1:])
    atomic_write_bytes(file, buf.getvalue())  # a fresh temp name of its own (never through a planted link)
    return file


def plot_experiment(spec: ExperimentSpec, records: list[dict], out_dir: Path) -> list[Path]:
    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=120)
    n_runs = 0
    for i, v in enumerate(spec.variants):
        recs = [r for r in records if r["variant"] == v.label]
        if not recs:
            continue
        n_runs = max(n_runs, len(recs))
        xs, ys = curves_on_grid(recs)
        if xs.size == 0:
            continue
        with np.errstate(all="ignore"):
            import warnings

            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                mean = np.nanmean(ys, axis=0)
                lo, hi = np.nanmin(ys, axis=0), np.nanmax(ys, axis=0)
        color = f"C{i % 10}"
        ax.plot(xs, mean, color=color, lw=1.6, label=f"{v.label} (mean of {len(recs)})")
        if len(recs) > 1:
            ax.fill_between(xs, lo, hi, color=color, alpha=0.15, lw=0)
    for label, y in spec.y_reference.items():
        ax.axhline(y, color="k", ls="--", lw=0.8)
        ax.annotate(label, (ax.get_xlim()[0], y), xytext=(4, 3), textcoords="offset points", fontsize=8)
    for label, x in spec.x_reference.items():
        ax.axvline(x, color="k", ls=":", lw=0.9)
        ax.annotate(label, (x, ax.get_ylim()[0]), xytext=(4, 6), textcoords="offset points", fontsize=8,
                    rotation=90)
    ax.set_xlabel(spec.x_label)
    ax.set_ylabel(spec.y_label)
    ax.set_title(f"{spec.name}: {spec.title}\n(thesis {spec.section}; shaded: min-max over runs)", fontsize=9)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:  # no runs drawn: no legend (matplotlib would warn)
        ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    paths = [save_figure(fig, out_dir / f"curve.{ext}") for ext in ("png", "svg")]
    plt.close(fig)
    return paths


def plot_from_disk(spec: ExperimentSpec, out: Path) -> list[Path]:
    """Redraw the plot of the latest ``connrl run`` from the run records named in summary.json."""
    def left_out(path: Path, reason: str) -> None:
        print(f"connrl: warning: {path} is damaged ({reason}); left out of the plot", file=sys.stderr)

    summary, records = stored_runs(spec, out, left_out)  # a damaged summary raises DamagedFile
    if summary is None:
        raise FileNotFoundError(f"{out / spec.name / 'summary.json'} not found: run `connrl run {spec.name}` first")
    missing = missing_runs(spec.name, summary, records)
    if missing:
        print(f"connrl: warning: {missing}; the plot shows the others (`connrl run` with the summary's profile "
              "redoes them)", file=sys.stderr)
    return plot_experiment(spec, records, out / spec.name)
