"""Which sources a compiled kernel depends on, and their fingerprint: one stamp per module.

A compiled kernel carries the code of every function it calls and the values of the module
globals it reads, and it can reach only what its module imports when it is loaded. The cache
of a kernel is therefore keyed on :func:`module_stamp` of the module that defines it: a hash of
that module's source and of the stamps of the hcomc modules it imports at its top level
(:func:`top_level_imports`, read with :mod:`ast`; imports inside functions and under
``if TYPE_CHECKING:`` cannot reach compiled code). An edit recompiles exactly the kernels of
the edited module and of the modules that import it, directly or not; an edit of a module no
kernel module imports (the command line, the experiments, a controller's Python code)
recompiles nothing. The kernel layer's import rule (``tests/test_layers.py``) keeps these
closures small: a module that defines kernels imports only numpy, numba, :mod:`hcomc._jit`
and other kernel modules.
"""

from __future__ import annotations

import ast
import hashlib
import re
from functools import cache
from pathlib import Path

COMPILING = ("numba", "hcomc._jit")
"""Imports that mark a module as one that defines compiled kernels."""

_COMPILING_LINE = re.compile(r"^(?:from|import)[ \t]+(?:numba\b|hcomc\._jit\b)", re.M)


def module_name(path: Path, package: Path) -> str:
    """Dotted name of the module in ``path`` (``<package name>.a.b``; a package's
    ``__init__.py`` is the package)."""
    parts = path.relative_to(package).with_suffix("").parts
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join([package.name, *parts])


@cache
def _modules(package: Path) -> dict[str, Path]:
    """Dotted module name -> its file, for every file of ``package`` (once per process)."""
    return {module_name(path, package): path for path in sorted(package.rglob("*.py"))}


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _statements(body: list[ast.stmt]) -> list[ast.stmt]:
    """The statements that run when a module is loaded: its top level, with the branches of
    ``if``/``try`` blocks, but not ``if TYPE_CHECKING:`` (annotations only)."""
    found: list[ast.stmt] = []
    for node in body:
        if isinstance(node, ast.If):
            found.extend(_statements(node.orelse if _is_type_checking(node) else node.body))
            if not _is_type_checking(node):
                found.extend(_statements(node.orelse))
        elif isinstance(node, ast.Try):
            for block in (node.body, node.orelse, node.finalbody, *(h.body for h in node.handlers)):
                found.extend(_statements(block))
        else:
            found.append(node)
    return found


def top_level_imports(path: Path, package: Path) -> set[str]:
    """The modules of ``package`` that the module in ``path`` imports when it is loaded
    (``from a import b`` gives ``a.b`` when that is a module, else ``a``; relative imports made
    absolute)."""
    modules = _modules(package)
    name = module_name(path, package)
    here = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found: set[str] = set()
    for node in _statements(ast.parse(path.read_bytes(), filename=str(path)).body):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join([*here[: len(here) - node.level + 1], *filter(None, [base])])
            found.update(
                f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else base
                for alias in node.names
            )
    return {_owner(target, modules) for target in found} - {name, package.name, ""}


def _owner(target: str, modules: dict[str, Path]) -> str:
    """The module of ``modules`` that ``target`` names or lies in (``""``: none)."""
    while target not in modules and "." in target:
        target = target.rpartition(".")[0]
    return target if target in modules else ""


def closure(name: str, package: Path) -> list[str]:
    """``name`` and every module of ``package`` it imports when loaded, directly or through
    others, sorted."""
    modules = _modules(package)
    seen = {name}
    todo = [name]
    while todo:
        for target in _imports(todo.pop(), package):
            if target not in seen:
                seen.add(target)
                todo.append(target)
    return sorted(seen & set(modules))


@cache
def _imports(name: str, package: Path) -> frozenset[str]:
    path = _modules(package).get(name)
    return frozenset() if path is None else frozenset(top_level_imports(path, package))


@cache
def module_stamp(name: str, package: Path) -> str:
    """SHA-256 of the paths and sources of ``name`` and of every module in its
    :func:`closure` (once per process): what a kernel defined in ``name`` is compiled from."""
    modules = _modules(package)
    digest = hashlib.sha256()
    for member in closure(name, package):
        path = modules[member]
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def kernel_modules(package: Path) -> list[str]:
    """The modules of ``package`` that define compiled kernels: they import numba or
    :mod:`hcomc._jit` at their top level (a line scan, then confirmed by
    :func:`top_level_imports`' parse)."""
    found = []
    for name, path in _modules(package).items():
        text = path.read_text(encoding="utf-8")
        if _COMPILING_LINE.search(text) and _compiles(path):
            found.append(name)
    return found


def _compiles(path: Path) -> bool:
    for node in _statements(ast.parse(path.read_bytes(), filename=str(path)).body):
        names = (
            [a.name for a in node.names]
            if isinstance(node, ast.Import)
            else [node.module or ""]
            if isinstance(node, ast.ImportFrom) and not node.level
            else []
        )
        if any(n == c or n.startswith(c + ".") for n in names for c in COMPILING):
            return True
    return False


def fingerprint(package: Path) -> str:
    """SHA-256 of the stamps of every kernel module of ``package``: it changes exactly when
    some kernel's cache goes stale."""
    digest = hashlib.sha256()
    for name in kernel_modules(package):
        digest.update(f"{name}={module_stamp(name, package)}\n".encode())
    return digest.hexdigest()


def forget_sources() -> None:
    """Forget the sources and stamps read so far (they are read once per process), for a
    process that edits the sources and stamps them again."""
    for cached in (_modules, _imports, module_stamp):
        cached.cache_clear()
