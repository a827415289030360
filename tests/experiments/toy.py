"""A toy experiment for the runner, spec and plot tests: importable by worker processes by name."""

import dataclasses
from dataclasses import dataclass

import numpy as np

from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant


@dataclass(frozen=True)
class ToyParams:
    n: int = 5
    explode_at: int | None = None


def toy_run(params, rng, progress):
    assert isinstance(params, ToyParams)  # the worker rebuilds the spec's parameter class
    draws = rng.random(params.n)
    progress(params.n, params.n)
    return RunResult(list(range(params.n)), list(np.cumsum(draws)), {"total": float(draws.sum())},
                     rows=[{"i": i, "draw": float(d)} for i, d in enumerate(draws)])


CALLS = []


def counting_run(params, rng, progress):
    CALLS.append(params.n)
    if params.explode_at == len(CALLS):
        raise KeyboardInterrupt
    return toy_run(params, rng, progress)


def spec(run="tests.experiments.toy:toy_run"):
    return ExperimentSpec(
        name="toy", title="toy", section="-", run=run, params=ToyParams(),
        profiles={"tiny": {"runs": 2}, "quick": {"runs": 3}, "full": {"runs": 4, "n": 7}},
        variants=(Variant("a", {}, {"total": 2.0}), Variant("b/c", {"n": 6})),
        quantities=(Quantity("total", "sum of draws", "higher"),))


@dataclass(frozen=True)
class ToyParamsGrown(ToyParams):
    """ToyParams with a parameter declared later: at its default it is ToyParams's behaviour (``m`` is unused)."""

    m: int = 3


@dataclass(frozen=True)
class ToyParamsNewDefault(ToyParams):
    n: int = 6


def grown_spec(params=ToyParamsGrown()):
    return dataclasses.replace(spec(), params=params)
