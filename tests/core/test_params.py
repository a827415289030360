"""A parameter is declared once (``connrl.core.params.param``): its range and choices are checked from the
declaration, a subclass that changes a default keeps them, and the run key reads the declared defaults."""

import hashlib
import json
from dataclasses import dataclass

import pytest

from connrl.core.params import check_types, declared, defaults, param, run_key


@dataclass(frozen=True)
class Base:
    task: str = param(choices=("A", "B"), note="which task")
    lr: float = param(0.05, ">0", "learning rate (5.3.3)")
    lam: float = param(0.7, "0..1")
    trials: int = param(300, ">=1")
    plain: float = 1.0

    def __post_init__(self):
        check_types(self)


@dataclass(frozen=True)
class Child(Base):
    lr: float = 0.04  # a new default only: the declaration is Base's


def test_ranges_and_choices_come_from_the_declaration():
    assert Base("A").lr == 0.05
    for bad, message in (({"lr": 0.0}, "parameter lr must be > 0, got 0.0"),
                         ({"lam": 1.5}, r"parameter lam must be in \[0, 1\], got 1.5"),
                         ({"trials": 0}, "parameter trials must be >= 1, got 0"),
                         ({"trials": 2.0}, r"parameter trials must be a whole number in \[1, 1000000\], got 2.0"),
                         ({"task": "C"}, "parameter task must be one of 'A', 'B', got 'C'")):
        with pytest.raises(ValueError, match=message):
            Base(**{"task": "A", **bad})
    assert Base("B", plain=-5.0).plain == -5.0  # undeclared: its annotation only


def test_a_subclass_changing_a_default_keeps_the_declaration():
    assert Child("A").lr == 0.04
    with pytest.raises(ValueError, match="parameter lr must be > 0"):
        Child("A", lr=-1.0)
    with pytest.raises(ValueError, match="parameter task must be one of"):
        Child("Z")
    assert declared(Child, "lr", "note") == "learning rate (5.3.3)" and declared(Child, "plain", "range") is None
    assert defaults(Child) == {"lr": 0.04, "lam": 0.7, "trials": 300, "plain": 1.0}  # task has none


def test_an_unknown_range_is_refused_where_it_is_declared():
    with pytest.raises(ValueError, match="unknown range '>1'; allowed: >0, >=0, >=1, 0..1, 0..<1, 0..180"):
        param(1, ">1")


@dataclass(frozen=True)
class Grown(Child):
    m: int = param(3, ">=0", "declared later, at the default that keeps the old behaviour")


def test_the_run_key_hashes_only_what_differs_from_the_defaults():
    digest = lambda d: hashlib.sha256(json.dumps(d, sort_keys=True).encode()).hexdigest()[:10]  # noqa: E731
    assert run_key(Child("A")) == digest({"task": "A"}) == run_key(Grown("A"))  # task has no default: always in
    assert run_key(Child("A", lam=0.5)) == digest({"task": "A", "lam": 0.5}) == run_key(Grown("A", lam=0.5))
    assert run_key(Grown("A", m=4)) == digest({"task": "A", "m": 4})
    assert run_key(Child("A", lr=0.05)) == digest({"task": "A", "lr": 0.05})  # Base's default, not Child's
