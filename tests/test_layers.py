"""The package's layering and size limits, read from the source with ``ast`` (no connrl module is imported).

Layers, lowest first: ``connrl.core`` / ``connrl.nets`` / ``connrl.agents`` (the thesis's algorithms, knowing no
world) and ``connrl.envs`` (the worlds, knowing no learner) below ``connrl.tasks`` (wiring), then
``connrl.experiments``, ``connrl.report`` and ``connrl.cli``. Every ``import`` counts, at module level or inside a
function.

How an import statement becomes edges of the module graph:

* ``import connrl.a.b`` and ``from connrl.a.b import name`` depend on ``connrl.a.b`` (a package means its
  ``__init__``);
* ``from connrl.a import b`` where ``connrl/a/b.py`` (or ``connrl/a/b/``) exists depends on ``connrl.a.b``,
  not on ``connrl.a``;
* relative imports are resolved against the importing module's package;
* the parent packages Python also initialises on the way (``connrl.a`` for ``connrl.a.b``) are not edges:
  a package's ``__init__`` re-exporting its own submodules would otherwise make every sibling import a cycle;
* ``importlib.import_module`` (the experiment registry, run functions named by string) is not seen.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "connrl"

MAX_FILE_LINES = 520
MAX_FUNCTION_LINES = 60
# modules allowed past MAX_FILE_LINES besides the compiled kernels (name contains "kernel"), with the reason
LONG_MODULES_ALLOWED: dict[str, str] = {}

# (importing layer, layers it must not import); a layer is a dotted prefix
FORBIDDEN = {
    "connrl.core": ("connrl.envs", "connrl.tasks", "connrl.experiments", "connrl.report", "connrl.cli"),
    "connrl.nets": ("connrl.envs", "connrl.tasks", "connrl.experiments", "connrl.report", "connrl.cli"),
    "connrl.agents": ("connrl.envs", "connrl.tasks", "connrl.experiments", "connrl.report", "connrl.cli"),
    # the own-task API knows the learners, not the thesis's worlds or experiments
    "connrl.own": ("connrl.envs", "connrl.tasks", "connrl.experiments", "connrl.report", "connrl.cli"),
    # the worlds know no learner: of connrl they may use only themselves and connrl.storage
    "connrl.envs": ("connrl.core", "connrl.nets", "connrl.agents", "connrl.tasks", "connrl.experiments",
                    "connrl.report", "connrl.cli"),
}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES: dict[str, Path] = {module_name(p): p for p in sorted(ROOT.rglob("*.py"))}
TREES: dict[str, ast.Module] = {m: ast.parse(p.read_text(), filename=str(p)) for m, p in MODULES.items()}


def in_layer(module: str, layer: str) -> bool:
    return module == layer or module.startswith(layer + ".")


@dataclass(frozen=True)
class Edge:
    source: str
    target: str
    line: int
    name: str | None  # for ``from M import name`` where name is not a submodule: the name looked up in M

    def where(self) -> str:
        return f"{MODULES[self.source].relative_to(ROOT.parent)}:{self.line}"


def _absolute(module: str, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    package = module.split(".") if MODULES[module].name == "__init__.py" else module.split(".")[:-1]
    base = package[:len(package) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports_of(module: str) -> list[Edge]:
    """Every import of a connrl module in ``module``, at any depth."""
    out = []
    for node in ast.walk(TREES[module]):
        if isinstance(node, ast.Import):
            out += [Edge(module, a.name, node.lineno, None) for a in node.names if in_layer(a.name, "connrl")]
        elif isinstance(node, ast.ImportFrom):
            base = _absolute(module, node)
            if not in_layer(base, "connrl"):
                continue
            for a in node.names:
                sub = f"{base}.{a.name}"
                if sub in MODULES:
                    out.append(Edge(module, sub, node.lineno, None))
                else:
                    out.append(Edge(module, base, node.lineno, None if a.name == "*" else a.name))
    return out


EDGES: list[Edge] = [e for m in MODULES for e in imports_of(m)]


def test_the_modules_are_found():
    assert {"connrl", "connrl.core.replay", "connrl.envs.robot", "connrl.envs.robot.sim", "connrl.cli"} <= set(MODULES)
    assert any(e.source == "connrl.core.replay" and e.target == "connrl.core.replay_kernel" for e in EDGES), \
        "function-level imports must count"


def test_layers_do_not_import_upward():
    offenders = [f"{e.where()}: {e.source} imports {e.target}" for e in EDGES
                 for layer, banned in FORBIDDEN.items()
                 if in_layer(e.source, layer) and any(in_layer(e.target, b) for b in banned)]
    assert not offenders, "imports across the layers:\n" + "\n".join(offenders)


def test_only_tasks_wire_a_world_to_a_learner():
    """Outside ``connrl.tasks`` no module imports both a world (``connrl.envs``) and an agent (``connrl.agents``)."""
    offenders = []
    for m in MODULES:
        if in_layer(m, "connrl.tasks"):
            continue
        targets = [e.target for e in EDGES if e.source == m]
        if any(in_layer(t, "connrl.envs") for t in targets) and any(in_layer(t, "connrl.agents") for t in targets):
            offenders.append(m)
    assert not offenders, f"modules that import both connrl.envs and connrl.agents outside connrl.tasks: {offenders}"


def _top_level_names(tree: ast.Module) -> set[str]:
    names = set()
    for node in ast.walk(tree):  # includes names bound under if/try at module level
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update((a.asname or a.name).split(".")[0] for a in node.names)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
    return names


def test_every_connrl_import_resolves():
    """Imports inside functions run only when called: a stale one (a moved module or name) is caught here."""
    defined = {m: _top_level_names(t) for m, t in TREES.items()}
    missing = [f"{e.where()}: {e.target}" + (f".{e.name}" if e.name else "") for e in EDGES
               if e.target not in MODULES or (e.name is not None and e.name not in defined[e.target])]
    assert not missing, "imports of connrl modules or names that do not exist:\n" + "\n".join(missing)


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module, or a module importing itself (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out = []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph.get(v, ()):
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_cycle_finder_finds_cycles():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"a"}, "b": {"a"}}) == [["a"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles():
    graph: dict[str, set[str]] = {m: set() for m in MODULES}
    for e in EDGES:
        if e.target in MODULES:
            graph[e.source].add(e.target)
    cycles = _cycles(graph)
    lines = []
    for comp in cycles:
        inner = [f"    {e.where()}: {e.source} -> {e.target}" for e in EDGES if e.source in comp and e.target in comp]
        lines += [" <-> ".join(comp), *inner]
    assert not cycles, "import cycles among connrl modules:\n" + "\n".join(lines)


def test_no_module_is_too_long():
    offenders = []
    for m, p in MODULES.items():
        n = len(p.read_text().splitlines())
        if n > MAX_FILE_LINES and "kernel" not in p.stem and m not in LONG_MODULES_ALLOWED:
            offenders.append(f"{p.relative_to(ROOT.parent)}: {n} lines")
    assert not offenders, f"modules over {MAX_FILE_LINES} lines (split them, or list them in " \
                          "LONG_MODULES_ALLOWED with the reason):\n" + "\n".join(offenders)


def _is_njit(decorator: ast.expr) -> bool:
    target = decorator.func if isinstance(decorator, ast.Call) else decorator
    return ast.unparse(target) in ("numba.njit", "nb.njit", "njit")  # ``import numba as nb`` in envs/robot


def test_no_function_is_too_long():
    offenders = []
    for p in MODULES.values():
        for node in ast.walk(ast.parse(p.read_text())):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            n = node.end_lineno - node.lineno + 1
            if n > MAX_FUNCTION_LINES and not any(_is_njit(d) for d in node.decorator_list):
                offenders.append(f"{p.relative_to(ROOT.parent)}:{node.lineno} {node.name}: {n} lines")
    assert not offenders, f"functions over {MAX_FUNCTION_LINES} lines (not numba.njit):\n" + "\n".join(offenders)
