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
    "connrl.experiments.recharge",
    "connrl.experiments.recharge_flat",
    "connrl.experiments.complexity",
    "connrl.experiments.integration",
    "connrl.experiments.steps",
)


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
