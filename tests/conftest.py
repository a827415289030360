"""Shared fixtures: tiny-profile runs of registered experiments, stored once per test session (and worker)."""

from pathlib import Path

import pytest

from tests.tiny_runs import run_tiny


@pytest.fixture(scope="session")
def tiny_runs(tmp_path_factory):
    """``tiny_runs(*names)`` runs each named experiment on the tiny profile once into a shared folder and returns
    that folder. Tests must not change what is stored there."""
    out = tmp_path_factory.mktemp("tiny-runs")
    done: set[str] = set()

    def run(*names: str) -> Path:
        for name in names:
            if name not in done:
                run_tiny(name, out)
                done.add(name)
        return out

    return run
