"""Declarative experiment specs: one per thesis figure or table.

A spec names the run function (``"module:function"``, so worker processes can import it), its parameters
as a frozen dataclass (the full profile), each profile's overrides, the variants (the curves of a figure or
the rows of a table, as overrides) and the quantities a run reports, each with the thesis's reference value.
Overrides are applied with ``dataclasses.replace``; a key the parameter class does not have is refused when
the spec is built, with the allowed keys in the message. The runner turns a spec into independent runs
(variant x seed), executes them in parallel, and writes per-run records and ``summary.json``.

A run function has the signature ``run(params, rng: numpy.random.Generator, progress) -> RunResult`` where
``params`` is an instance of the spec's parameter class and ``progress(done, total)`` may be called to drive
the live display.
"""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from connrl.core.params import (  # noqa: F401  (the parameter classes' tools, re-exported)
    CAPS,
    MAX_COUNT,
    MAX_UNITS,
    MAX_WINDOW,
    as_dict,
    cap,
    check_sequence,
    check_types,
    declared,
    field_kinds,
    param,
    run_key,
)

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


def override(params, changes: Mapping[str, Any], where: str = "parameters"):
    """``dataclasses.replace(params, **changes)``, refusing a key the parameter class does not have and a value
    its annotation does not allow (checked by ``check_types``), before anything runs. A whole-number float for an
    int field (``--set trials=1e4``) is taken as that int; any other float there is refused by ``check_types``."""
    fields = {f.name: field_kinds(f) for f in dataclasses.fields(params)}
    unknown = sorted(set(changes) - set(fields))
    if unknown:
        raise ValueError(f"{where}: unknown parameter(s) {', '.join(map(repr, unknown))}; allowed: "
                         f"{', '.join(fields)}")
    changes = {k: _whole(fields[k], v) for k, v in changes.items()}
    try:
        return dataclasses.replace(params, **changes)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None


def _whole(kinds: list[str], value):
    """A float that is exactly a whole number, for a field that takes an int and no float, as that int (floats
    above 2^53 are not exact and stay floats, to be refused by the type check with the field's range)."""
    if isinstance(value, float) and "int" in kinds and "float" not in kinds and value.is_integer() \
            and abs(value) <= 2**53:
        return int(value)
    return value


def check_combination(params, where: str = "parameters"):
    """A complete parameter set's checks across fields (``params.check_combination()``, where a class has one:
    e.g. no more taught lessons than a task has), which a partial set such as a spec's base cannot pass."""
    check = getattr(params, "check_combination", None)
    if check is not None:
        try:
            check()
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None
    return params


@dataclass(frozen=True)
class ExperimentSpec:
    name: str  # CLI name, e.g. "pole-full"
    title: str  # one line, e.g. "Memoryless QCON-R on full-state pole balancing"
    section: str  # thesis section, e.g. "7.5.4 fn. 4"
    run: str  # "module:function" of the run function
    params: Any  # a frozen parameter dataclass: the full profile
    profiles: Mapping[str, Mapping[str, Any]]  # profile -> overrides, each with "runs"
    variants: tuple[Variant, ...]
    quantities: tuple[Quantity, ...]
    x_label: str = "trials"
    y_label: str = ""
    description: str = ""
    y_reference: Mapping[str, float] = field(default_factory=dict)  # horizontal lines on the plot
    x_reference: Mapping[str, float] = field(default_factory=dict)  # vertical lines on the plot
    seed: int = 0  # the first seed its stored results use (`connrl reproduce`); development or fresh-seed checks differ
    full_runs: int | None = None  # runs per variant of its stored full-profile results, where not the profile's

    def __post_init__(self):
        if not dataclasses.is_dataclass(self.params) or isinstance(self.params, type):
            raise TypeError(f"experiment {self.name}: params must be a parameter dataclass instance")
        missing = [p for p in PROFILES if p not in self.profiles]
        if missing:
            raise ValueError(f"experiment {self.name}: profiles {missing} are missing")
        for p, over in self.profiles.items():
            if "runs" not in over:
                raise ValueError(f"experiment {self.name}: profile {p!r} must set 'runs'")
            base = override(self.params, {k: v for k, v in over.items() if k != "runs"},
                            f"experiment {self.name}, profile {p!r}")
            for v in self.variants:
                check_combination(override(base, v.params, f"experiment {self.name}, variant {v.label!r}"),
                                  f"experiment {self.name}, variant {v.label!r}")

    def resolve(self, profile: str, runs: int | None = None) -> tuple[Any, int]:
        """Parameters and run count for a profile (``runs`` overrides the profile's)."""
        if profile not in self.profiles:
            raise ValueError(f"unknown profile {profile!r}; allowed: {', '.join(self.profiles)}")
        over = dict(self.profiles[profile])
        n = over.pop("runs")
        if runs is not None:
            if runs < 1:
                raise ValueError(f"--runs must be >= 1, got {runs}")
            n = runs
        return override(self.params, over, f"experiment {self.name}, profile {profile!r}"), n

    def variant_params(self, base, variant: Variant):
        """The parameters of one variant on top of a resolved profile."""
        return override(base, variant.params, f"experiment {self.name}, variant {variant.label!r}")

    def run_function(self) -> Callable:
        return load_callable(self.run)


def load_callable(ref: str) -> Callable:
    module, _, attr = ref.partition(":")
    return getattr(importlib.import_module(module), attr)


def qualified_name(obj) -> str:
    """``"module:QualName"`` of a class, for ``load_callable`` in a worker process."""
    cls = obj if isinstance(obj, type) else type(obj)
    return f"{cls.__module__}:{cls.__qualname__}"
