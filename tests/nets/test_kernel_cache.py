"""No cached Numba kernel can run stale code (issue 25).

``numba.njit(cache=True)`` reuses a compiled kernel until *its own* source file changes. Whatever it compiled in from
elsewhere (another kernel it calls, which Numba inlines, or a global constant, which Numba freezes) is not part of
that check: edit the other file and the cached kernel keeps running the old code. The rule that makes this
impossible: everything a cached kernel reads from a global, and everything the kernels it calls read, is defined in
the cached kernel's own file (library modules such as ``math`` and ``numpy`` aside: Numba's version keys the cache).
Compiled functions that call each other therefore live in one module (``connrl.nets.kernels`` for the OAON's
arithmetic and its whole-lesson replay); a kernel that must call into another file cannot be cached.
"""

from __future__ import annotations

import ast
import importlib
import math
import pkgutil
import types
from functools import cache
from pathlib import Path

import numba
import numpy as np
from numba.core.caching import NullCache
from numba.core.registry import CPUDispatcher

import connrl
from connrl.envs.robot.constants import SONAR_MAX
from connrl.nets.mlp import _mlp_forward


def _all_dispatchers() -> list[CPUDispatcher]:
    found = {}
    for info in pkgutil.walk_packages(connrl.__path__, "connrl."):
        module = importlib.import_module(info.name)
        for obj in vars(module).values():
            if isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == module.__name__:
                found[id(obj)] = obj
    return list(found.values())


def _is_cached(d: CPUDispatcher) -> bool:
    return not isinstance(d._cache, NullCache)


@cache
def _imported_names(filename: str) -> frozenset[str]:
    """Names a module binds by ``import`` at its top level (not by an assignment or definition of its own)."""
    tree = ast.parse(Path(filename).read_text())
    own, imported = set(), set()
    for node in tree.body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            imported.update((a.asname or a.name).split(".")[0] for a in node.names)
        else:
            for sub in ast.walk(node):
                if isinstance(sub, ast.Name) and isinstance(sub.ctx, ast.Store):
                    own.add(sub.id)
                elif isinstance(sub, (ast.FunctionDef, ast.ClassDef)):
                    own.add(sub.name)
    return frozenset(imported - own)


def _names(code: types.CodeType) -> set[str]:
    out = set(code.co_names)
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            out |= _names(c)
    return out


def foreign_reads(d: CPUDispatcher) -> list[str]:
    """What ``d`` compiles in, directly or through the kernels it calls, from outside its own source file."""
    home = d.py_func.__code__.co_filename
    out, seen, todo = [], set(), [d]
    while todo:
        k = todo.pop()
        f = k.py_func
        if id(k) in seen:
            continue
        seen.add(id(k))
        where = f"{f.__module__}.{f.__qualname__}"
        for name in sorted(_names(f.__code__)):
            if name not in f.__globals__:
                continue  # an attribute, a builtin or a local
            g = f.__globals__[name]
            if isinstance(g, CPUDispatcher):
                if g.py_func.__code__.co_filename != home:
                    out.append(f"{where} calls {g.py_func.__module__}.{g.py_func.__qualname__}")
                else:
                    todo.append(g)
            elif isinstance(g, types.ModuleType):
                if g.__name__.split(".")[0] == "connrl":
                    out.append(f"{where} reads the connrl module {g.__name__}")
            elif name in _imported_names(f.__code__.co_filename):
                out.append(f"{where} reads {name}, imported from another file")
    return out


def test_no_cached_kernel_compiles_in_code_or_constants_from_another_file():
    kernels = [d for d in _all_dispatchers() if _is_cached(d)]
    assert len(kernels) > 20  # the walk found them (mlp, replay, recurrent, worlds, ...)
    offenders = sorted({line for d in kernels for line in foreign_reads(d)})
    assert not offenders, ("cached kernels whose cache would not notice an edit of another file (move the code into "
                           "one module, or drop cache=True):\n" + "\n".join(offenders))


@numba.njit
def _calls_another_file(x):
    return _mlp_forward(x, x, 0, x, x)


_OWN = 3.0


@numba.njit
def _reads_constants():
    return SONAR_MAX + _OWN + math.pi + np.pi


def test_the_check_sees_calls_and_constants_from_other_files():
    assert foreign_reads(_calls_another_file) == [
        f"{__name__}._calls_another_file calls {_mlp_forward.py_func.__module__}._mlp_forward"]
    assert foreign_reads(_reads_constants) == [
        f"{__name__}._reads_constants reads SONAR_MAX, imported from another file"]
