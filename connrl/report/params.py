"""Parameters as Markdown tables, read from their one declaration (``connrl.core.params.param``): per experiment
(``connrl params NAME``: each value of the full profile, what it allows, which profiles and variants set it otherwise,
and its note: where the thesis states it, or R, reconstructed) or per parameter class (``connrl params``, the source
of docs/PARAMETERS.md)."""

from __future__ import annotations

import dataclasses

from connrl.core.params import allowed_text, declared, defaults
from connrl.experiments.spec import ExperimentSpec


def _row(cells) -> str:
    return "| " + " | ".join(str(c).replace("|", "\\|").replace("\n", " ") for c in cells) + " |"


def _name(cls: type) -> str:
    return f"{cls.__module__}.{cls.__qualname__}"


def experiment_table(spec: ExperimentSpec) -> str:
    """One experiment's parameters: the full profile's values and what else sets them."""
    base, cls = spec.resolve("full")[0], type(spec.params)
    lines = [f"### {spec.name}: {spec.title} ({spec.section})", "",
             f"`{_name(cls)}`, at the full profile; the other profiles and the variants set the ones named.", "",
             "| parameter | full | allowed | set by | note |", "|---|---|---|---|---|"]
    for f in dataclasses.fields(base):
        by = [f"{p}: {over[f.name]!r}" for p, over in spec.profiles.items() if f.name in over]
        by += [f"{v.label}: {v.params[f.name]!r}" for v in spec.variants if f.name in v.params]
        lines.append(_row((f.name, repr(getattr(base, f.name)), allowed_text(cls, f), "; ".join(by),
                           declared(cls, f.name, "note") or "")))
    return "\n".join(lines) + "\n"


def class_tables(specs: dict[str, ExperimentSpec]) -> str:
    """Every parameter class the experiments use: each field's default, what it allows, its note, and the
    experiments built on the class."""
    users: dict[type, list[str]] = {}
    for name, spec in sorted(specs.items()):
        users.setdefault(type(spec.params), []).append(name)
    out = ["# Parameters", "", "Every parameter class of the experiments, read from its declaration "
           "(`connrl.core.params.param`). Made by `connrl params > docs/PARAMETERS.md`; `connrl params NAME` gives one "
           "experiment's values with what its profiles and variants set. A note marked R is a reconstruction "
           "(docs/RECONSTRUCTION.md); `allowed` is what a `--set` or a sweep may give.", ""]
    for cls, names in sorted(users.items(), key=lambda kv: _name(kv[0])):
        out += [f"## `{_name(cls)}`", "", "Used by: " + ", ".join(f"`{n}`" for n in names) + ".", "",
                "| parameter | default | allowed | note |", "|---|---|---|---|"]
        given = defaults(cls)
        out += [_row((f.name, repr(given[f.name]) if f.name in given else "(required)", allowed_text(cls, f),
                      declared(cls, f.name, "note") or "")) for f in dataclasses.fields(cls)]
        out.append("")
    return "\n".join(out)
