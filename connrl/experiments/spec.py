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
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from connrl.nets.mlp import MAX_UNITS as NET_MAX_UNITS

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


def field_kinds(field: dataclasses.Field) -> list[str]:
    """The type names of a parameter field's annotation (``"float | None"`` -> ``["float", "None"]``); the
    parameter modules use postponed annotations, so these are strings."""
    return [k.strip() for k in str(field.type).split("|")]


_KINDS = {"bool": (bool,), "int": (int,), "float": (int, float), "str": (str,), "tuple": (tuple,), "dict": (dict,)}


_RANGES = {">0": (lambda v: v > 0, "> 0"), ">=0": (lambda v: v >= 0, ">= 0"), ">=1": (lambda v: v >= 1, ">= 1"),
           "0..1": (lambda v: 0 <= v <= 1, "in [0, 1]"), "0..<1": (lambda v: 0 <= v < 1, "in [0, 1)"),
           "0..180": (lambda v: 0 <= v <= 180, "in [0, 180]")}

# Upper bounds of the size-like parameters (issue 24): every int parameter is at most MAX_COUNT, and a parameter named
# in CAPS (an int, or a float that sizes something) at most its cap; check_types refuses a larger value before any run.
# Generous: every profile and variant of every experiment stays within a tenth of its cap
# (tests/experiments/test_bounds.py), while no single value can ask for gigabytes or for years of compute.
MAX_COUNT = 10**7  # any count: steps spent pre-training, states of a grid, ...
MAX_UNITS = NET_MAX_UNITS  # hidden or context units of one net (the thesis's largest: 30): one cap everywhere
MAX_WINDOW = 100  # window sizes: the last N steps kept as input or for stuck detection (the thesis's: 5 and 8)
CAPS = {
    **dict.fromkeys(("hidden", "context"), MAX_UNITS),
    "hidden_fraction": 10.0,  # hidden units per input (Ch. 5: 0.3)
    "stuck_window": MAX_WINDOW,
    # trials, plays, epochs, and the trial counts that pace them (the thesis's most: 1000 trials)
    **dict.fromkeys(("trials", "max_trials", "anneal_trials", "train_plays", "copy_epochs", "test_every",
                     "planning_block", "freeze_at", "freeze_after_optimal"), 10**6),
    # steps of one trial or test, or one lesson's length (the most: 5001 steps of a pole test)
    **dict.fromkeys(("max_steps", "train_max_steps", "test_steps", "steps"), 10**6),
    # lessons taught, kept for replay, replayed per trial (the most: 100)
    **dict.fromkeys(("lessons", "capacity", "lessons_per_trial", "model_lessons_per_trial"), 10**5),
    # test tasks and environments, paths and samples recorded (the most: 8000 environments of 4.3.4)
    **dict.fromkeys(("test_tasks", "test_envs", "eval_envs", "tests_per_room", "final_tests_per_room", "paths",
                     "probe_samples"), 10**5),
    "block_max": 10**6,  # grids' regions of odd side up to block_max (n = 3^j states, j <= 12: ComplexityParams)
}


def cap(name: str, kinds: list[str]) -> float | None:
    """The largest value parameter ``name`` may take (None: not a size)."""
    return CAPS.get(name, MAX_COUNT if "int" in kinds else None)


def _allowed(name: str, kinds: list[str], rng: str | None) -> str:
    """``"in [1, 1000000]"``, or ``"at most 10000000"`` without a lower bound."""
    top = cap(name, kinds)
    if rng == ">0":
        return f"in (0, {top}]" if "float" in kinds else f"in [1, {top}]"
    return f"in [{rng[2:]}, {top}]" if rng in (">=0", ">=1") else f"at most {top}"


def check_types(params, ranges: Mapping[str, str] | None = None, **choices: tuple) -> None:
    """Refuse a field whose value does not match its annotation (``float``, ``int | None``, ...; a bool is not
    a number), lies outside its range in ``ranges`` (``">0"``, ``">=0"``, ``">=1"``, ``"0..1"``, ``"0..<1"``,
    ``"0..180"``; None passes where the annotation allows it), exceeds its cap (``cap``: every int, and the floats
    named in ``CAPS``) or, for the fields named in ``choices``, is not one of the allowed values. Parameter classes
    call it from ``__post_init__``, so a bad value fails when the spec (or a sweep) is built, before any run."""
    ranges = ranges or {}
    for f in dataclasses.fields(params):
        v = getattr(params, f.name)
        kinds = field_kinds(f)
        ok = (v is None and "None" in kinds) or any(
            isinstance(v, _KINDS.get(k, object)) and not (isinstance(v, bool) and k in ("int", "float"))
            for k in kinds if k != "None")
        if not ok and "int" in kinds and "float" not in kinds:
            raise ValueError(f"parameter {f.name} must be a whole number {_allowed(f.name, kinds, ranges.get(f.name))}"
                             f"{' or None' if 'None' in kinds else ''}, got {v!r}")
        if not ok:
            raise ValueError(f"parameter {f.name} must be {f.type}, got {v!r}")
        if isinstance(v, float) and not math.isfinite(v):
            raise ValueError(f"parameter {f.name} must be a finite number, got {v!r}")
        if f.name in ranges and v is not None and not _RANGES[ranges[f.name]][0](v):
            raise ValueError(f"parameter {f.name} must be {_RANGES[ranges[f.name]][1]}, got {v!r}")
        top = cap(f.name, kinds)
        if top is not None and isinstance(v, (int, float)) and not isinstance(v, bool) and v > top:
            raise ValueError(f"parameter {f.name} must be {_allowed(f.name, kinds, ranges.get(f.name))}, got {v!r}")
        if f.name in choices and v not in choices[f.name]:
            raise ValueError(f"parameter {f.name} must be one of {', '.join(map(repr, choices[f.name]))}, got {v!r}")


def check_sequence(name: str, values, kind: type, low: float, high: float, longest: int) -> None:
    """Refuse a tuple parameter (e.g. ``probe_steps``) with more than ``longest`` entries or an entry that
    is not a ``kind`` (a bool is not a number) in [low, high]."""
    if len(values) > longest:
        raise ValueError(f"parameter {name} must have at most {longest} entries, got {len(values)}")
    for x in values:
        if isinstance(x, bool) or not isinstance(x, kind) or not low <= x <= high:
            what = "whole numbers" if kind is int else "numbers"
            raise ValueError(f"parameter {name} must hold {what} in [{low}, {high}], got {x!r}")


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


def as_dict(params) -> dict[str, Any]:
    """The plain-data form of a parameter set, as stored in run records and hashed into run folders."""
    return {f.name: getattr(params, f.name) for f in dataclasses.fields(params)}


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
