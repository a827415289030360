"""Declarative experiment specs: one per thesis figure or table.

A spec names the run function (``"module:function"``, so worker processes can import it), the parameters
of each profile, the variants (the curves of a figure or the rows of a table) and the quantities a run
reports, each with the thesis's reference value. The runner turns a spec into independent runs
(variant x seed), executes them in parallel, and writes per-run records, ``summary.json`` and a plot.

A run function has the signature ``run(params: dict, rng: numpy.random.Generator, progress) -> RunResult``
where ``progress(done, total)`` may be called to drive the live display.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

PROFILES = ("tiny", "quick", "full")


@dataclass(frozen=True)
class Quantity:
    """A reproduced number: its per-run values go into summary.json beside the thesis's value."""

    name: str  # key in RunResult.metrics
    description: str  # one line for tables
    better: str = "lower"  # "lower" or "higher": which way beats the thesis
    section: str = ""  # where the thesis states it


@dataclass(frozen=True)
class Variant:
    """One curve of a figure / row of a table: parameter overrides and the thesis's numbers for it."""

    label: str
    params: Mapping[str, Any] = field(default_factory=dict)
    thesis: Mapping[str, float] = field(default_factory=dict)  # quantity name -> thesis value


@dataclass
class RunResult:
    """What one run returns: a learning curve, the quantities, and free-form rows for the CSV."""

    curve_x: list[float]
    curve_y: list[float]
    metrics: dict[str, float | None]
    rows: list[dict[str, Any]] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class ExperimentSpec:
    name: str  # CLI name, e.g. "pole-full"
    title: str  # one line, e.g. "Memoryless QCON-R on full-state pole balancing"
    section: str  # thesis section, e.g. "7.5.4 fn. 4"
    run: str  # "module:function" of the run function
    params: Mapping[str, Any]  # parameters of the full profile
    profiles: Mapping[str, Mapping[str, Any]]  # profile -> overrides, each with "runs"
    variants: tuple[Variant, ...]
    quantities: tuple[Quantity, ...]
    x_label: str = "trials"
    y_label: str = ""
    description: str = ""
    y_reference: Mapping[str, float] = field(default_factory=dict)  # horizontal lines on the plot
    x_reference: Mapping[str, float] = field(default_factory=dict)  # vertical lines on the plot

    def __post_init__(self):
        missing = [p for p in PROFILES if p not in self.profiles]
        if missing:
            raise ValueError(f"experiment {self.name}: profiles {missing} are missing")
        for p, over in self.profiles.items():
            if "runs" not in over:
                raise ValueError(f"experiment {self.name}: profile {p!r} must set 'runs'")

    def resolve(self, profile: str, runs: int | None = None) -> tuple[dict, int]:
        """Parameters and run count for a profile (``runs`` overrides the profile's)."""
        if profile not in self.profiles:
            raise ValueError(f"unknown profile {profile!r}; allowed: {', '.join(self.profiles)}")
        over = dict(self.profiles[profile])
        n = over.pop("runs")
        if runs is not None:
            if runs < 1:
                raise ValueError(f"--runs must be >= 1, got {runs}")
            n = runs
        return {**self.params, **over}, n

    def run_function(self) -> Callable:
        return load_callable(self.run)


def load_callable(ref: str) -> Callable:
    module, _, attr = ref.partition(":")
    return getattr(importlib.import_module(module), attr)
