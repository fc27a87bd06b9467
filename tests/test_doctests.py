"""Every example in hcomc's docstrings runs and shows what it says (doctest), and none is
hidden from doctest (e.g. in the docstring of an object doctest does not look into)."""

from __future__ import annotations

import doctest
import importlib
import re
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PROMPT = re.compile(r"^\s*>>> ", re.M)


def _modules_with_examples() -> list[tuple[str, int]]:
    """(module, number of example lines) of every source file with a ``>>>`` line."""
    found = []
    for path in sorted((SRC / "hcomc").rglob("*.py")):
        count = len(PROMPT.findall(path.read_text(encoding="utf-8")))
        if count:
            parts = path.relative_to(SRC).with_suffix("").parts
            found.append((".".join(p for p in parts if p != "__init__"), count))
    return found


MODULES = _modules_with_examples()


def test_the_package_has_examples():
    assert sum(n for _, n in MODULES) >= 30


@pytest.mark.parametrize(("name", "lines"), MODULES, ids=[m for m, _ in MODULES])
def test_docstring_examples_run(name: str, lines: int) -> None:
    module = importlib.import_module(name)
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    result = doctest.testmod(module, optionflags=flags, verbose=False, report=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed"
    assert result.attempted == lines, (
        f"{name}: {lines} example lines in the source, {result.attempted} run by doctest"
    )
