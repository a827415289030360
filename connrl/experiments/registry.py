"""All experiments, by name: every module of ``connrl.experiments`` that defines ``EXPERIMENTS: list[ExperimentSpec]``
(and ``CHAPTER``, the thesis chapter they belong to) is found here, so a new figure's module needs no entry."""

from __future__ import annotations

import functools
import importlib
import pkgutil
from pathlib import Path

from connrl.experiments.spec import ExperimentSpec


@functools.cache
def spec_modules() -> tuple:
    """The experiment modules, chapter by chapter (by name within one)."""
    found = []
    for info in pkgutil.iter_modules([str(Path(__file__).parent)], "connrl.experiments."):
        module = importlib.import_module(info.name)
        if "EXPERIMENTS" in vars(module):  # its own, not one it imports
            if not isinstance(getattr(module, "CHAPTER", None), int):
                raise TypeError(f"{info.name} defines EXPERIMENTS but no CHAPTER (the thesis chapter, an int)")
            found.append(module)
    return tuple(sorted(found, key=lambda m: (m.CHAPTER, m.__name__)))


def chapters() -> list[int]:
    """The thesis chapters that have experiments."""
    return sorted({m.CHAPTER for m in spec_modules()})


def by_chapter(chapters) -> list[ExperimentSpec]:
    """The experiments of the given chapters, chapter by chapter in the registry's order."""
    wanted = set(chapters)
    return [spec for m in spec_modules() if m.CHAPTER in wanted for spec in m.EXPERIMENTS]


def all_experiments() -> dict[str, ExperimentSpec]:
    out: dict[str, ExperimentSpec] = {}
    for module in spec_modules():
        for spec in module.EXPERIMENTS:
            if spec.name in out:
                raise ValueError(f"experiment name {spec.name!r} is defined twice")
            out[spec.name] = spec
    return out


def get_experiment(name: str) -> ExperimentSpec:
    specs = all_experiments()
    if name not in specs:
        raise KeyError(f"unknown experiment {name!r}; available: {', '.join(sorted(specs))}")
    return specs[name]
