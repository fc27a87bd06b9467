"""Imports only run downwards through the package's layers.

cli -> viz -> experiments/envs/robustness/sumo -> metrics -> sim -> control -> interface ->
safety/models/optim -> config/corridor/road (plus the small utilities ``rng``, ``_typing``,
``_jit``, ``_stamp`` and ``_compiling``). Imports inside functions count, since they run;
imports under ``if TYPE_CHECKING:`` (for annotations only) count too.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "hcomc"

LAYERS = {
    "cli": 8,
    "__main__": 8,
    "viz": 7,
    "experiments": 6,
    "robustness": 6,
    # The SUMO co-simulation is an engine the experiments and the robustness campaign run
    # (imported only when engine="sumo" is asked for, so SUMO stays an optional extra); its
    # faulted form applies the robustness layer's faults, hence the same layer.
    "sumo": 6,
    # CommonRoad's scenario format: an exporter of the runs, beside the SUMO exports
    "commonroad": 6,
    "envs": 6,
    "metrics": 5,
    "sim": 4,
    "control": 3,
    "interface": 2,
    "safety": 1,
    "models": 1,
    "optim": 1,
    "config": 0,
    "corridor": 0,
    "road": 0,
    "rng": 0,
    "_typing": 0,
    "_jit": 0,
    "_stamp": 0,
    "_compiling": 0,
    "equations": 0,
}
ROOT_NAMES = {"__version__"}  # names defined in hcomc/__init__.py itself (layer 0)


def _layer(module: str) -> int | None:
    """Layer of an hcomc module (None for other packages and the package root)."""
    parts = module.split(".")
    if parts[0] != "hcomc" or len(parts) == 1 or parts[1] in ROOT_NAMES:
        return None
    if parts[1] not in LAYERS:
        raise AssertionError(f"hcomc.{parts[1]} has no layer: add it to LAYERS")
    return LAYERS[parts[1]]


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _runtime_imports(tree: ast.AST) -> list[tuple[str, int]]:
    """(imported module, line) of every import that runs, skipping TYPE_CHECKING blocks."""
    found: list[tuple[str, int]] = []

    def visit(node: ast.AST) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child):
                for stmt in child.orelse:
                    visit(ast.Module(body=[stmt], type_ignores=[]))
                continue
            if isinstance(child, ast.Import):
                found.extend((alias.name, child.lineno) for alias in child.names)
            elif isinstance(child, ast.ImportFrom) and child.module and child.level == 0:
                found.append((child.module, child.lineno))
                # `from hcomc.control import fifo` imports the module hcomc.control.fifo
                found.extend((f"{child.module}.{a.name}", child.lineno) for a in child.names)
            visit(child)

    visit(tree)
    return found


def _annotation_imports(tree: ast.AST) -> list[tuple[str, int]]:
    """(imported module, line) of every import inside an ``if TYPE_CHECKING:`` block."""
    found: list[tuple[str, int]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and _is_type_checking(node):
            for stmt in node.body:
                if isinstance(stmt, ast.Import):
                    found.extend((alias.name, stmt.lineno) for alias in stmt.names)
                elif isinstance(stmt, ast.ImportFrom) and stmt.module and stmt.level == 0:
                    found.append((stmt.module, stmt.lineno))
                    found.extend((f"{stmt.module}.{a.name}", stmt.lineno) for a in stmt.names)
    return found


def _modules() -> list[tuple[str, Path]]:
    out = []
    for path in sorted(SRC.rglob("*.py")):
        name = ".".join(("hcomc", *path.relative_to(SRC).with_suffix("").parts))
        out.append((name.removesuffix(".__init__"), path))
    return out


def _upward_imports(module: str, path: Path) -> list[str]:
    mine = _layer(module)
    if mine is None:
        return []
    bad = []
    for target, line in _runtime_imports(ast.parse(path.read_text(encoding="utf-8"))):
        theirs = _layer(target)
        if theirs is not None and theirs > mine:
            bad.append(f"{path.relative_to(SRC.parent)}:{line}: {module} imports {target}")
    return bad


@pytest.mark.parametrize(("module", "path"), _modules(), ids=[m for m, _ in _modules()])
def test_no_import_runs_upwards(module: str, path: Path) -> None:
    assert _upward_imports(module, path) == []


def _upward_annotation_imports() -> set[tuple[str, str]]:
    """(module, imported module) of every annotation-only import that runs upwards (the
    imported module as far as it is a module of hcomc: ``hcomc.sim.engine``, not its class)."""
    modules = {m for m, _ in _modules()}
    found = set()
    for module, path in _modules():
        mine = _layer(module)
        for target, _ in _annotation_imports(ast.parse(path.read_text(encoding="utf-8"))):
            theirs = _layer(target)
            upward = mine is not None and theirs is not None and theirs > mine
            if upward and target in modules:
                found.add((module, target))
    return found


def test_no_annotation_import_runs_upwards() -> None:
    assert _upward_annotation_imports() == set()


def test_the_check_sees_lazy_upward_imports() -> None:
    code = (
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n"
        "    from hcomc.viz.common import new_figure\n"
        "def f():\n"
        "    from hcomc.sim import engine\n"
        "    import hcomc.metrics\n"
    )
    found = _runtime_imports(ast.parse(code))
    assert ("hcomc.viz.common", 3) not in found
    assert ("hcomc.viz.common", 3) in _annotation_imports(ast.parse(code))
    assert ("hcomc.sim.engine", 5) in found
    assert ("hcomc.metrics", 6) in found
    assert [t for t, _ in found if _layer(t) is not None and _layer(t) > LAYERS["control"]] == [
        "hcomc.sim",
        "hcomc.sim.engine",
        "hcomc.metrics",
    ]


def _module_level_imports(module: str, path: Path, modules: set[str]) -> set[str]:
    """The modules of hcomc that ``module`` imports when it is loaded: statements at its top
    level, outside ``if TYPE_CHECKING:`` (``from a import b`` counts ``a.b`` when that is a
    module, else ``a``)."""
    found = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.update(
                f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in modules else node.module
                for a in node.names
            )
    return {m for m in found if m in modules and m != module}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of ``graph`` with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = [stack.pop()]
            while component[-1] != v:
                component.append(stack.pop())
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_cycle_between_modules_at_load_time() -> None:
    """Inside a layer too, modules import each other one way: none imports, when loaded, a
    module that imports it back (directly or through others)."""
    modules = dict(_modules())
    graph = {m: _module_level_imports(m, p, set(modules)) for m, p in modules.items()}
    assert _cycles(graph) == []


def test_the_cycle_check_finds_a_cycle() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": set()}
    assert _cycles(graph) == [["a", "b", "c"]]


def _all_imports(path: Path, modules: set[str]) -> set[str]:
    """Every module ``path`` imports anywhere, lazy and annotation-only imports included: the
    hcomc module a name comes from (``from a import b`` gives ``a.b`` when that is a module,
    else ``a``), or the top-level name of another package."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = set()
    for target, _ in _runtime_imports(tree) + _annotation_imports(tree):
        if target.partition(".")[0] != "hcomc":
            found.add(target.partition(".")[0])
            continue
        module = target
        while module not in modules and "." in module:
            module = module.rpartition(".")[0]
        found.add(module)
    return found - {"hcomc"}


def test_no_import_cycle_at_all() -> None:
    """No module imports, at load time, inside a function or for annotations, a module that
    imports it back (directly or through others)."""
    modules = dict(_modules())
    graph = {m: _all_imports(p, set(modules)) & set(modules) - {m} for m, p in modules.items()}
    assert _cycles(graph) == []


KERNEL_PACKAGES = frozenset({"numpy", "numba"})
"""The packages besides the standard library that the kernel layer may import."""


def _defines_kernels(path: Path) -> bool:
    """Whether the module compiles kernels: it imports numba or :mod:`hcomc._jit` when loaded."""
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        names = (
            [a.name for a in node.names]
            if isinstance(node, ast.Import)
            else [node.module or ""]
            if isinstance(node, ast.ImportFrom)
            else []
        )
        if any(n == "hcomc._jit" or n.partition(".")[0] == "numba" for n in names):
            return True
    return False


def _kernel_layer() -> tuple[set[str], dict[str, set[str]]]:
    """The kernel layer: the largest set of hcomc modules that import (anywhere, annotations
    included) only the standard library, numpy, numba and one another; and every module's
    imports."""
    modules = dict(_modules())
    imports = {m: _all_imports(p, set(modules)) - {m} for m, p in modules.items()}
    allowed = set(sys.stdlib_module_names) | KERNEL_PACKAGES
    layer = set(modules)
    while True:
        out = {m for m in layer if any(t not in layer and t not in allowed for t in imports[m])}
        if not out:
            return layer, imports
        layer -= out


def test_kernel_modules_import_only_the_kernel_layer() -> None:
    """A module that defines compiled kernels imports only numpy, numba, the JIT helper, the
    equations and other modules of the kernel layer: no config, engine classes or registry,
    so that a kernel's cache stamp (its module and what that imports) is as small as its
    code."""
    layer, imports = _kernel_layer()
    outside = {
        module: sorted(t for t in imports[module] if t not in layer and t.startswith("hcomc"))
        for module, path in _modules()
        if _defines_kernels(path) and module not in layer
    }
    assert outside == {}
