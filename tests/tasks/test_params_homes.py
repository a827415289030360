"""Each parameter class lives beside the builders that read it (issue 46): every builder of ``connrl.tasks`` that
takes a parameter set ``p`` is annotated with the classes declared in ``connrl.tasks``, every ``p.NAME`` it reads
is a field of each of them, and every experiment passes its builders an instance of one (or of a subclass)."""

from __future__ import annotations

import ast
import dataclasses
import inspect
import textwrap
import typing
from pathlib import Path

import pytest

from connrl.experiments.registry import all_experiments
from connrl.tasks import hidden_state, integration, pole, recharge, robot

TASKS = Path(pole.__file__).resolve().parent
MODULES = (pole, hidden_state, robot, recharge, integration)


def builders() -> list:
    """Every function of the wiring modules that takes a parameter set ``p``."""
    return [f for m in MODULES for _, f in inspect.getmembers(m, inspect.isfunction)
            if f.__module__ == m.__name__ and "p" in inspect.signature(f).parameters]


def p_classes(fn) -> tuple[type, ...]:
    hint = typing.get_type_hints(fn)["p"]
    return typing.get_args(hint) or (hint,)


def reads(fn) -> set[str]:
    """The NAMEs of every ``p.NAME`` in the builder's body."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
    return {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute) and isinstance(n.value, ast.Name)
            and n.value.id == "p"}


def test_there_are_builders_and_no_protocols_left():
    assert len(builders()) >= 15
    for m in MODULES:
        assert "Protocol" not in Path(m.__file__).read_text(), m.__name__


@pytest.mark.parametrize("fn", builders(), ids=lambda f: f"{f.__module__}.{f.__name__}")
def test_a_builder_reads_only_fields_of_the_classes_it_is_given(fn):
    for cls in p_classes(fn):
        assert dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen, cls
        assert cls.__module__.startswith("connrl.tasks."), cls  # declared beside the builders
        names = {f.name for f in dataclasses.fields(cls)}
        assert reads(fn) <= names, (cls.__name__, sorted(reads(fn) - names))


def test_every_experiments_parameters_are_declared_beside_a_builder_or_extend_one():
    homes = {c for fn in builders() for c in p_classes(fn)}
    for name, spec in all_experiments().items():
        cls = type(spec.params)
        if cls.__module__.startswith(("connrl.experiments.survival", "connrl.experiments.complexity",
                                      "connrl.experiments.td_depth", "connrl.experiments.behaviours")):
            continue  # their run functions build their worlds from plain arguments, not from ``p``
        assert issubclass(cls, tuple(homes)), (name, cls)


def test_no_getattr_fallbacks_on_parameters():
    """A parameter is a field of its class (a new one moves no stored run: ``connrl.core.params.run_key``), not
    ``getattr(p, name, default)``."""
    for path in [*TASKS.glob("*.py"), *(TASKS.parent / "experiments").glob("*.py")]:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "getattr" \
                    and isinstance(node.args[0], ast.Name) and node.args[0].id == "p" and len(node.args) == 3:
                raise AssertionError(f"{path.name}:{node.lineno}: getattr(p, ..., default)")
