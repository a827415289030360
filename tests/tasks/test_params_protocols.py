"""The builders of ``connrl.tasks`` state the parameters they read as ``typing.Protocol`` classes (issue 25): every
builder's ``p`` is annotated with one, and the experiments' parameter dataclasses passed to it have every member,
of the declared type, without ``getattr`` fallbacks."""

from __future__ import annotations

import ast
import inspect
import types
import typing
from pathlib import Path

import pytest

from connrl.experiments.hidden_state import CupParams, FrozenModelParams, PoleHiddenParams
from connrl.experiments.integration import IntegrationParams
from connrl.experiments.pole import PoleParams
from connrl.experiments.recharge import OwnLibraryParams, RechargeParams
from connrl.experiments.recharge_bound import BoundParams
from connrl.experiments.recharge_flat import FlatParams
from connrl.experiments.robot import RobotParams
from connrl.experiments.robot_bounds import CopyParams
from connrl.tasks import hidden_state, integration, pole, recharge, robot

TASKS = Path(pole.__file__).resolve().parent
MODULES = (pole, hidden_state, robot, recharge, integration)

# builder -> the parameter classes the experiments pass to it
PASSED = {
    pole.make_envs: (PoleParams, PoleHiddenParams),
    pole.make_agent: (PoleParams,),
    hidden_state.table_entry: (CupParams, PoleHiddenParams, FrozenModelParams),
    hidden_state.make_agent: (CupParams, PoleHiddenParams, FrozenModelParams),
    robot.make_env: (RobotParams, CopyParams),
    robot.make_agent: (RobotParams, CopyParams),
    robot.world_of: (RobotParams, CopyParams),
    recharge.make_recharge_env: (RechargeParams, OwnLibraryParams, BoundParams),
    recharge.make_high_level_agent: (RechargeParams, IntegrationParams),
    recharge.cooling: (RechargeParams, IntegrationParams),
    recharge.make_flat_env: (FlatParams,),
    recharge.make_flat_agent: (FlatParams,),
    integration.n_inputs: (IntegrationParams,),
    integration.make_integration_env: (IntegrationParams,),
    integration.make_recurrent_agent: (IntegrationParams,),
    integration.make_integration_agent: (IntegrationParams,),
}


def builders() -> list:
    """Every function of the wiring modules that takes a parameter set ``p``."""
    return [f for m in MODULES for _, f in inspect.getmembers(m, inspect.isfunction)
            if f.__module__ == m.__name__ and "p" in inspect.signature(f).parameters]


def p_protocol(fn) -> type:
    return typing.get_type_hints(fn)["p"]


def members(proto: type) -> dict[str, object]:
    """name -> declared type of every read-only member of a protocol, its bases' included."""
    out = {}
    for cls in reversed(proto.__mro__):
        for name, v in vars(cls).items():
            if isinstance(v, property):
                out[name] = typing.get_type_hints(v.fget)["return"]
    return out


def has_type(v, t) -> bool:
    args = typing.get_args(t) if isinstance(t, types.UnionType) else (t,)
    return any(v is None if a is type(None) else isinstance(v, typing.get_origin(a) or a) for a in args)


def test_every_builder_is_listed_and_annotated_with_a_protocol():
    assert set(builders()) == set(PASSED)
    for fn in builders():
        proto = p_protocol(fn)
        assert getattr(proto, "_is_protocol", False) and proto.__module__.startswith("connrl.tasks."), fn
        assert members(proto), proto


@pytest.mark.parametrize("fn", list(PASSED), ids=lambda f: f"{f.__module__}.{f.__name__}")
def test_the_parameter_classes_passed_have_every_member_of_its_type(fn):
    proto = p_protocol(fn)
    for cls in PASSED[fn]:
        p = cls()
        for name, t in members(proto).items():
            assert has_type(getattr(p, name), t), (cls.__name__, name, getattr(p, name), t)


def test_no_getattr_fallbacks_on_parameters():
    """A parameter is a field of its class (a new one moves no stored run: ``connrl.core.params.run_key``), not
    ``getattr(p, name, default)``."""
    for path in [*TASKS.glob("*.py"), *(TASKS.parent / "experiments").glob("*.py")]:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "getattr" \
                    and isinstance(node.args[0], ast.Name) and node.args[0].id == "p" and len(node.args) == 3:
                raise AssertionError(f"{path.name}:{node.lineno}: getattr(p, ..., default)")
