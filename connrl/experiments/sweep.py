"""``connrl sweep``: one experiment's parameters with overrides, one run per seed, through the runner.

A sweep checks a setting over many seeds beside the thesis protocol (the measurements quoted in
docs/RESULTS.md and docs/notes/ that justify a deviation or support an analysis). It takes the experiment's
full-profile parameters (optionally one of its variants), applies ``--set key=value`` overrides (refused
before any compute when a key is unknown), and runs seed A .. B-1, each seeded
``numpy.random.default_rng(seed)`` as ``connrl run`` seeds its runs. Runs are stored, resumable and
parallel like any experiment's, under ``OUT/sweep-NAME-HASH/``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from typing import Any

from connrl.experiments.spec import ExperimentSpec, Variant, as_dict, check_combination, field_kinds, override
from connrl.experiments.store import MAX_RUNS


def parse_assignment(text: str) -> tuple[str, Any]:
    """``key=value``; the value is read as JSON (numbers, true/false, null, lists, objects) or else a string."""
    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise ValueError(f"--set expects key=value, got {text!r}")
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
        value = raw
    return key.strip(), value


def parse_seeds(text: str) -> tuple[int, int]:
    """``A:B`` -> (A, B): seeds A .. B-1."""
    a, sep, b = text.partition(":")
    try:
        first, stop = int(a), int(b)
    except ValueError:
        raise ValueError(f"--seeds expects A:B with whole numbers (seeds A..B-1), got {text!r}") from None
    if not sep or first < 0 or stop <= first:
        raise ValueError(f"--seeds expects A:B with 0 <= A < B (seeds A..B-1), got {text!r}")
    if stop - first > MAX_RUNS:
        raise ValueError(f"--seeds asks for {stop - first} runs; at most {MAX_RUNS}")
    return first, stop


def _typed(kinds: list[str], value):
    """JSON has no float-valued whole numbers and no tuples: ``1`` for a float field is 1.0, a list for a tuple
    field a tuple (the annotation decides; anything else is checked by the parameter class)."""
    if "float" in kinds and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if "tuple" in kinds and isinstance(value, list):
        return tuple(value)
    return value


def sweep_spec(spec: ExperimentSpec, assignments: list[str], variant: str | None = None) -> ExperimentSpec:
    """A one-variant spec: ``spec``'s full-profile parameters, ``variant``'s overrides, then ``assignments``."""
    base = spec.params
    label = "base"
    if variant is not None:
        match = [v for v in spec.variants if v.label == variant]
        if not match:
            raise ValueError(f"experiment {spec.name} has no variant {variant!r}; variants: "
                             + ", ".join(repr(v.label) for v in spec.variants))
        base = spec.variant_params(base, match[0])
        label = variant
    kinds = {f.name: field_kinds(f) for f in dataclasses.fields(base)}
    changes = dict(parse_assignment(a) for a in assignments)
    changes = {k: _typed(kinds.get(k, []), v) for k, v in changes.items()}
    params = check_combination(override(base, changes, f"sweep of {spec.name}"), f"sweep of {spec.name}")
    # named by the resulting parameters: the same setting, however spelt, reuses its runs
    digest = hashlib.sha256(json.dumps(as_dict(params), sort_keys=True, default=str).encode()).hexdigest()[:8]
    title = label + "".join(f", {k}={v}" for k, v in changes.items())
    return dataclasses.replace(spec, name=f"sweep-{spec.name}-{digest}", title=f"sweep of {spec.name}: {title}",
                               params=params, profiles={p: {"runs": 1} for p in spec.profiles},
                               variants=(Variant("sweep"),))
