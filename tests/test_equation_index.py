"""The equation index of docs/models.md is complete and current.

The table between ``<!-- equation index -->`` and ``<!-- /equation index -->`` has one row per
equation of the paper (Eq. 1 to Eq. 19): number, what it is, the dotted path of the one
public function that implements it, and the test that checks that function. Here every
number appears exactly once, every function imports and states its equation in its
docstring, and every test exists. Nothing is called: importing hcomc compiles no kernel, so
this runs in seconds.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import re
from functools import cache
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "docs" / "models.md"
EQUATIONS = range(1, 20)  # the paper's Eq. 1 … Eq. 19
PACKAGE = "hcomc.equations."  # every equation's one home

START, END = "<!-- equation index -->", "<!-- /equation index -->"
ROW = re.compile(r"^\|\s*(\d+)\s*\|(.*?)\|\s*`([\w.]+)`\s*\|\s*`([^`]+)`\s*\|$")
# "Eq. 7", "Eq. (1)", "Eqs. (4)-(6)", "Eq. 8-13", "Eq. 9–10": a number or an inclusive range
CITATION = re.compile(r"\bEqs?\.\s?\(?(\d+)\)?(?:\s?[-–]\s?\(?(\d+)\)?)?")

# Equations whose function does not state its number in its own docstring yet, only the
# docstring of the module that defines it. When the function's docstring gains the number,
# the row is checked like the others: remove it here.


def _index_rows() -> list[tuple[int, str, str, str]]:
    """``(equation, what, dotted path, test)`` of every row of the index table."""
    text = MODELS.read_text(encoding="utf-8")
    assert text.count(START) == 1, f"{START} once"
    assert text.count(END) == 1, f"{END} once"
    block = text[text.index(START) + len(START) : text.index(END)]
    lines = [line.strip() for line in block.strip().splitlines()]
    assert lines[:2] == ["| Eq. | what it is | function | test |", "|---|---|---|---|"], lines[:2]
    rows = []
    for line in lines[2:]:
        match = ROW.match(line)
        assert match, f"malformed index row: {line}"
        number, what, path, test = match.groups()
        assert what.strip(), f"Eq. {number}: empty description"
        rows.append((int(number), what.strip(), path, test))
    return rows


ROWS = _index_rows()


def _ids(row: tuple[int, str, str, str]) -> str:
    return f"eq{row[0]}"


def _resolve(path: str) -> Any:
    """The object at a dotted path: the longest importable module prefix, then attributes."""
    parts = path.split(".")
    for k in range(len(parts), 0, -1):
        name = ".".join(parts[:k])
        try:
            obj: Any = importlib.import_module(name)
        except ModuleNotFoundError as error:
            if error.name is None or not name.startswith(error.name):
                raise  # the module exists but something it imports does not
            continue
        for name in parts[k:]:
            obj = getattr(obj, name)
        return obj
    raise ImportError(path)


def _python_function(obj: Any) -> Any:
    """The Python function behind ``obj``: itself, or a numba dispatcher's ``py_func``."""
    func = getattr(obj, "py_func", obj)
    assert inspect.isfunction(func), f"{obj!r} is not a function or a compiled kernel"
    return func


def cites(doc: str | None, number: int) -> bool:
    """Whether ``doc`` names Eq. ``number`` alone or within a range ("Eq. 8-13")."""
    for match in CITATION.finditer(doc or ""):
        first = int(match.group(1))
        last = int(match.group(2) or first)
        if first <= number <= last:
            return True
    return False


@cache
def _test_names(path: Path) -> frozenset[str]:
    """``name`` of every test function and ``Class::name`` of every test method in a file."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            names.add(node.name)
        elif isinstance(node, ast.ClassDef):
            names.update(
                f"{node.name}::{item.name}"
                for item in node.body
                if isinstance(item, ast.FunctionDef | ast.AsyncFunctionDef)
            )
    return frozenset(names)


def test_citation_pattern() -> None:
    assert cites("IDM acceleration, paper Eq. (1).", 1)
    assert not cites("IDM acceleration, paper Eq. (1).", 15)
    assert not cites("Eq. 15 for one pair", 1)
    assert cites("Lateral position, Eqs. (4)-(6).", 5)
    assert cites("virtual vehicles (paper Eq. 8-13)", 11)
    assert cites("a cubic for Eq. 9–10", 10)
    assert not cites("a cubic for Eq. 9–10", 11)
    assert not cites("see eq-15 in the label", 15)


def test_every_equation_appears_exactly_once() -> None:
    numbers = [row[0] for row in ROWS]
    assert sorted(numbers) == list(EQUATIONS), numbers


def test_every_equation_lives_in_the_equations_package() -> None:
    outside = [(number, path) for number, _, path, _ in ROWS if not path.startswith(PACKAGE)]
    assert outside == []


@pytest.mark.parametrize("row", ROWS, ids=_ids)
def test_function_imports_and_states_its_equation(row: tuple[int, str, str, str]) -> None:
    number, _, path, _ = row
    assert not any(part.startswith("_") for part in path.split(".")), f"{path} is not public"
    func = _python_function(_resolve(path))
    assert cites(func.__doc__, number), f"the docstring of {path} does not cite Eq. {number}"


@pytest.mark.parametrize("row", ROWS, ids=_ids)
def test_listed_test_exists(row: tuple[int, str, str, str]) -> None:
    number, _, _, test = row
    file, sep, name = test.partition("::")
    assert sep, f"Eq. {number}: '{test}' is not path::test_name"
    assert name, f"Eq. {number}: '{test}' names no test"
    path = ROOT / file
    assert path.is_file(), f"Eq. {number}: no file {file}"
    name = name.split("[", 1)[0]  # a parametrised case names its function
    assert name in _test_names(path), f"Eq. {number}: no test {name} in {file}"
    assert name.rpartition("::")[2].startswith("test"), f"Eq. {number}: {name} is not a test"
