"""Which source files the compiled kernels depend on, and their fingerprint.

A compiled kernel carries the code of every function it calls and the values of the module
globals it reads, and it can reach only what its module imports. The kernels therefore
depend on the files that compile (they import numba or :mod:`hcomc._jit`) and on every file
of the package those import, directly or not: :func:`kernel_sources`. The command line,
experiments, figures and the controllers' Python decision code lie outside it, so editing
them does not recompile the kernels.
"""

from __future__ import annotations

import ast
import hashlib
from collections.abc import Iterator
from pathlib import Path

COMPILING = ("numba", "hcomc._jit")
"""Imports that mark a file as one that defines or compiles kernels."""


def _module_file(package: Path, dotted: str) -> Path | None:
    """The file of module ``dotted`` (``<package name>.a.b``) inside ``package``, if any."""
    parts = dotted.split(".")
    if parts[0] != package.name:
        return None
    base = package.joinpath(*parts[1:])
    for candidate in (base / "__init__.py", base.with_suffix(".py")):
        if candidate.is_file():
            return candidate
    return None


def _imported_names(path: Path, package: Path) -> Iterator[str]:
    """Every dotted name ``path`` imports (``from a import b`` gives ``a`` and ``a.b``), with
    relative imports made absolute."""
    here = [package.name, *path.relative_to(package).parent.parts]
    for node in ast.walk(ast.parse(path.read_bytes(), filename=str(path))):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = here[: len(here) - node.level + 1] if node.level else []
            module = ".".join([*base, *([node.module] if node.module else [])])
            yield module
            yield from (f"{module}.{alias.name}" for alias in node.names)


def _dependencies(path: Path, package: Path) -> set[Path]:
    """The package's files that ``path`` imports, with the packages (``__init__.py``) on the
    way, which Python runs first."""
    found: set[Path] = set()
    for name in _imported_names(path, package):
        parts = name.split(".")
        for k in range(1, len(parts) + 1):
            file = _module_file(package, ".".join(parts[:k]))
            if file is not None:
                found.add(file)
    return found


def _compiles(path: Path) -> bool:
    names = set()
    for node in ast.walk(ast.parse(path.read_bytes(), filename=str(path))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names.add(node.module)
    return any(n == c or n.startswith(c + ".") for n in names for c in COMPILING)


def kernel_sources(package: Path) -> list[Path]:
    """The files of ``package`` that compile kernels and every file of it they import."""
    todo = [p for p in package.rglob("*.py") if _compiles(p)]
    seen: set[Path] = set()
    while todo:
        path = todo.pop()
        if path not in seen:
            seen.add(path)
            todo.extend(_dependencies(path, package) - seen)
    return sorted(seen)


def fingerprint(package: Path) -> str:
    """SHA-256 of the paths and contents of :func:`kernel_sources`."""
    digest = hashlib.sha256()
    for path in kernel_sources(package):
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()
