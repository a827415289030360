"""All experiments, by name. Each module listed here defines ``EXPERIMENTS: list[ExperimentSpec]``."""

from __future__ import annotations

import importlib

from connrl.experiments.spec import ExperimentSpec

SPEC_MODULES = (
    "connrl.experiments.pole",
    "connrl.experiments.survival",
    "connrl.experiments.hidden_state",
    "connrl.experiments.robot",
    "connrl.experiments.robot_bounds",
    "connrl.experiments.robot_noise",
    "connrl.experiments.td_depth",
    "connrl.experiments.recharge",
    "connrl.experiments.recharge_flat",
    "connrl.experiments.recharge_bound",
    "connrl.experiments.complexity",
    "connrl.experiments.integration",
    "connrl.experiments.steps",
)


# the thesis chapter each module's experiments belong to (`connrl reproduce --chapters`); the pole experiments are
# 7.5.4's (Appendix C's task)
CHAPTERS = {"connrl.experiments.survival": 4, "connrl.experiments.robot": 5, "connrl.experiments.robot_bounds": 5,
            "connrl.experiments.robot_noise": 5, "connrl.experiments.td_depth": 5,
            "connrl.experiments.recharge_flat": 6, "connrl.experiments.recharge": 6,
            "connrl.experiments.recharge_bound": 6, "connrl.experiments.complexity": 6,
            "connrl.experiments.pole": 7, "connrl.experiments.hidden_state": 7, "connrl.experiments.integration": 8,
            "connrl.experiments.steps": 8}


def by_chapter(chapters) -> list[ExperimentSpec]:
    """The experiments of the given chapters, chapter by chapter in the registry's order."""
    out = []
    for chapter in sorted(set(chapters)):
        for mod in (m for m in SPEC_MODULES if CHAPTERS[m] == chapter):
            out += list(importlib.import_module(mod).EXPERIMENTS)
    return out


def all_experiments() -> dict[str, ExperimentSpec]:
    out: dict[str, ExperimentSpec] = {}
    for mod in SPEC_MODULES:
        try:
            module = importlib.import_module(mod)
        except ModuleNotFoundError as exc:
            if exc.name == mod:  # a chapter not built yet
                continue
            raise
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
