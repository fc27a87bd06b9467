"""Which source files the compiled kernels depend on, and their fingerprint.

A compiled kernel carries the code of every function it calls and the values of the module
globals it reads, and it can reach only what its module imports. The kernels therefore
depend on the files that compile (they import numba or :mod:`hcomc._jit`) and on every file
of the package those import, directly or not: :func:`kernel_sources`. The command line,
experiments, figures and the controllers' Python decision code lie outside it, so editing
them does not recompile the kernels.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

COMPILING = ("numba", "hcomc._jit")
"""Imports that mark a file as one that defines or compiles kernels."""


def _modules(package: Path) -> dict[str, Path]:
    """Dotted module name (``<package name>.a.b``) -> its file, for every file of ``package``
    (a package's name maps to its ``__init__.py``)."""
    found = {}
    for path in package.rglob("*.py"):
        parts = path.relative_to(package).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join([package.name, *parts])] = path
    return found


_FROM = re.compile(r"^[ \t]*from[ \t]+(\.*[\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)", re.M)
_IMPORT = re.compile(r"^[ \t]*import[ \t]+([^\n]*)", re.M)


def _names(text: str) -> list[str]:
    """``a as b, c`` or ``(a, c)`` -> ``["a", "c"]``."""
    clean = re.sub(r"#[^\n]*", "", text).strip("()")
    return [n.split()[0] for n in clean.replace("\\", " ").split(",") if n.split()]


def _imported_names(path: Path, package: Path) -> set[str]:
    """Every dotted name ``path`` imports anywhere in it (``from a import b`` gives ``a`` and
    ``a.b``), with relative imports made absolute. A plain scan of the text, cheaper than
    parsing it (which every process that loads a kernel pays); a line in a
    docstring that looks like an import only adds a file to the stamp."""
    text = path.read_text(encoding="utf-8")
    here = [package.name, *path.relative_to(package).parent.parts]
    found: set[str] = set()
    for match in _FROM.finditer(text):
        module, names = match.group(1), _names(match.group(2))
        level = len(module) - len(module.lstrip("."))
        if level:
            module = ".".join([*here[: len(here) - level + 1], *filter(None, [module[level:]])])
        found.add(module)
        found.update(f"{module}.{name}" for name in names)
    for match in _IMPORT.finditer(text):
        found.update(_names(match.group(1)))
    return found


def _dependencies(names: set[str], modules: dict[str, Path]) -> set[Path]:
    """The files of ``modules`` among the imported ``names``, with the packages
    (``__init__.py``) on the way, which Python runs first."""
    found: set[Path] = set()
    for name in names:
        parts = name.split(".")
        found.update(
            modules[m] for k in range(1, len(parts) + 1) if (m := ".".join(parts[:k])) in modules
        )
    return found


def _compiles(names: set[str]) -> bool:
    return any(n == c or n.startswith(c + ".") for n in names for c in COMPILING)


def kernel_sources(package: Path) -> list[Path]:
    """The files of ``package`` that compile kernels and every file of it they import."""
    modules = _modules(package)
    imports = {p: _imported_names(p, package) for p in modules.values()}
    todo = [p for p, names in imports.items() if _compiles(names)]
    seen: set[Path] = set()
    while todo:
        path = todo.pop()
        if path not in seen:
            seen.add(path)
            todo.extend(_dependencies(imports[path], modules) - seen)
    return sorted(seen)


def fingerprint(package: Path) -> str:
    """SHA-256 of the paths and contents of :func:`kernel_sources`."""
    digest = hashlib.sha256()
    for path in kernel_sources(package):
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()
