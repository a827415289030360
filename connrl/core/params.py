"""Parameters declared once: a parameter class's field carries its default, its allowed range or values and where
the thesis states it (``param``); the checks, the tables (``connrl params NAME``) and the run folders' key
(``run_key``) all read that one declaration.

    @dataclass(frozen=True)
    class MyParams:
        lr: float = param(0.05, ">0", "back-propagation learning rate (5.3.3)")
        task: str = param("DP", choices=("DP", "DK"), note="the task (5.4)")

        def __post_init__(self):
            check_types(self)

A subclass that changes a default (``lr: float = 0.04``) keeps the declaration it overrides (``declared`` walks the
classes). A field without ``param`` is checked against its annotation and cap only.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from typing import Any

from connrl.nets.mlp import MAX_UNITS as NET_MAX_UNITS


def param(default: Any = dataclasses.MISSING, allowed: str | None = None, note: str = "", *,
          choices: tuple | None = None) -> Any:
    """A parameter field: its ``default`` (none: the field must be given), the range ``allowed`` (a key of
    ``_RANGES``: ``">0"``, ``">=0"``, ``">=1"``, ``"0..1"``, ``"0..<1"``, ``"0..180"``), the ``choices`` it must be
    one of, and a ``note``: what it is and where the thesis states it (``R``: reconstructed, docs/RECONSTRUCTION.md
    says why)."""
    if allowed is not None and allowed not in _RANGES:
        raise ValueError(f"unknown range {allowed!r}; allowed: {', '.join(_RANGES)}")
    return dataclasses.field(default=default, metadata={"range": allowed, "note": note, "choices": choices})


def declared(cls: type, name: str, what: str) -> Any:
    """Field ``name``'s declared ``what`` (``"range"``, ``"choices"``, ``"note"``) in ``cls`` or the nearest class
    it inherits the field from (a subclass may re-declare a field with a new default only); None if undeclared."""
    for c in cls.__mro__:
        f = getattr(c, "__dataclass_fields__", {}).get(name)
        if f is not None and f.metadata.get(what) is not None:
            return f.metadata[what]
    return None


def run_key(params) -> str:
    """The run folder's key: a hash of the values that differ from their class's defaults (a field with a default
    factory, such as a dict, is always hashed: declare a new parameter with a plain default). Declaring a new
    parameter, with the default that keeps the old behaviour, therefore moves no stored run; a changed default is
    caught by the run records, which store every value (``connrl.experiments.store.check_record``)."""
    return values_key(type(params), as_dict(params))


def values_key(cls: type, values: dict[str, Any]) -> str:
    """``run_key`` of a plain dict of values (entries that are no field of ``cls`` are always hashed)."""
    plain = {f.name: f.default for f in dataclasses.fields(cls) if f.default is not dataclasses.MISSING}
    changed = {k: v for k, v in values.items() if k not in plain or v != plain[k]}
    return hashlib.sha256(json.dumps(changed, sort_keys=True, default=str).encode()).hexdigest()[:10]


def defaults(cls: type) -> dict[str, Any]:
    """Every field's default, a factory's made afresh (a field without one is left out)."""
    out = {}
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            out[f.name] = f.default
        elif f.default_factory is not dataclasses.MISSING:
            out[f.name] = f.default_factory()
    return out


def field_kinds(field: dataclasses.Field) -> list[str]:
    """The type names of a parameter field's annotation (``"float | None"`` -> ``["float", "None"]``), postponed
    (a string) or not."""
    text = field.type.__name__ if isinstance(field.type, type) else str(field.type)
    return [k.strip() for k in text.split("|")]


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


def check_types(params) -> None:
    """Refuse a field whose value does not match its annotation (``float``, ``int | None``, ...; a bool is not
    a number), lies outside its declared range (``param``'s ``range``: ``">0"``, ``">=0"``, ``">=1"``, ``"0..1"``,
    ``"0..<1"``, ``"0..180"``; None passes where the annotation allows it), exceeds its cap (``cap``: every int,
    and the floats named in ``CAPS``) or is not one of its declared ``choices``. Parameter classes call it from
    ``__post_init__``, so a bad value fails when the spec (or a sweep) is built, before any run."""
    for f in dataclasses.fields(params):
        v = getattr(params, f.name)
        kinds = field_kinds(f)
        rng, choices = declared(type(params), f.name, "range"), declared(type(params), f.name, "choices")
        ok = (v is None and "None" in kinds) or any(
            isinstance(v, _KINDS.get(k, object)) and not (isinstance(v, bool) and k in ("int", "float"))
            for k in kinds if k != "None")
        if not ok and "int" in kinds and "float" not in kinds:
            raise ValueError(f"parameter {f.name} must be a whole number {_allowed(f.name, kinds, rng)}"
                             f"{' or None' if 'None' in kinds else ''}, got {v!r}")
        if not ok:
            raise ValueError(f"parameter {f.name} must be {f.type}, got {v!r}")
        if isinstance(v, float) and not math.isfinite(v):
            raise ValueError(f"parameter {f.name} must be a finite number, got {v!r}")
        if rng is not None and v is not None and not _RANGES[rng][0](v):
            raise ValueError(f"parameter {f.name} must be {_RANGES[rng][1]}, got {v!r}")
        top = cap(f.name, kinds)
        if top is not None and isinstance(v, (int, float)) and not isinstance(v, bool) and v > top:
            raise ValueError(f"parameter {f.name} must be {_allowed(f.name, kinds, rng)}, got {v!r}")
        if choices is not None and v not in choices:
            raise ValueError(f"parameter {f.name} must be one of {', '.join(map(repr, choices))}, got {v!r}")


def check_sequence(name: str, values, kind: type, low: float, high: float, longest: int) -> None:
    """Refuse a tuple parameter (e.g. ``probe_steps``) with more than ``longest`` entries or an entry that
    is not a ``kind`` (a bool is not a number) in [low, high]."""
    if len(values) > longest:
        raise ValueError(f"parameter {name} must have at most {longest} entries, got {len(values)}")
    for x in values:
        if isinstance(x, bool) or not isinstance(x, kind) or not low <= x <= high:
            what = "whole numbers" if kind is int else "numbers"
            raise ValueError(f"parameter {name} must hold {what} in [{low}, {high}], got {x!r}")


def as_dict(params) -> dict[str, Any]:
    """The plain-data form of a parameter set, as stored in run records and hashed into run folders."""
    return {f.name: getattr(params, f.name) for f in dataclasses.fields(params)}


def allowed_text(cls: type, field: dataclasses.Field) -> str:
    """What field ``field`` of ``cls`` allows, in words: its choices, its range (with its cap), or its type."""
    choices, rng, kinds = declared(cls, field.name, "choices"), declared(cls, field.name, "range"), field_kinds(field)
    if choices is not None:
        return "one of " + ", ".join(map(repr, choices))
    top = cap(field.name, kinds)
    text = _allowed(field.name, kinds, rng) if top is not None else (_RANGES[rng][1] if rng else "")
    return f"{' | '.join(kinds)} {text}".strip()
