"""Tiny-profile runs of registered experiments for tests, as ``connrl run NAME --profile tiny`` makes them."""

from pathlib import Path

from connrl.experiments.registry import get_experiment
from connrl.experiments.runner import RunOutcome, run_experiment
from connrl.report.plots import plot_experiment


def run_tiny(name: str, out: Path) -> RunOutcome:
    """What ``connrl run NAME --profile tiny --seed 0 --workers 1`` does, without the CLI: the runs, then the plot."""
    spec = get_experiment(name)
    outcome = run_experiment(spec, profile="tiny", out=out, workers=1, show_progress=False)
    plot_experiment(spec, outcome.records, Path(out) / name)
    return outcome
