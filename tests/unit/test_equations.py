"""hcomc.equations: the paper's equations, one home each, pure, documented; the old homes
(hcomc.models, hcomc.safety, hcomc.control.virtual_vehicle) re-export the same objects."""

from __future__ import annotations

import ast
import importlib
import inspect
import sys
from pathlib import Path

import pytest

from hcomc.equations.safety import stopping_distance

EQUATIONS = Path(__file__).resolve().parents[2] / "src" / "hcomc" / "equations"
MODULES = sorted(p.stem for p in EQUATIONS.glob("*.py") if p.stem != "__init__")
PUBLIC = [m for m in MODULES if not m.startswith("_")]
ALLOWED = {"numpy", "numba", "hcomc._jit", "hcomc._typing"}

# old module -> its counterpart in hcomc.equations
MOVED = {
    "hcomc.models.idm": "hcomc.equations.idm",
    "hcomc.models.iidm": "hcomc.equations.iidm",
    "hcomc.models.cav": "hcomc.equations.cav",
    "hcomc.models.following": "hcomc.equations.car_following",
    "hcomc.models.quintic": "hcomc.equations.lane_change",
    "hcomc.models.lane_change_peaks": "hcomc.equations.lane_change_peaks",
    "hcomc.models.transition": "hcomc.equations.transition",
    "hcomc.models.incentive": "hcomc.equations.incentive",
    "hcomc.models.ballistic": "hcomc.equations.integrate",
    "hcomc.models.fuel": "hcomc.equations.fuel",
    "hcomc.safety.collision": "hcomc.equations.collision",
    "hcomc.safety.collision_kernels": "hcomc.equations.collision",
    "hcomc.safety.critical": "hcomc.equations.safety",
    "hcomc.control.virtual_vehicle": "hcomc.equations.virtual_vehicle",
    "hcomc.optim.selection": "hcomc.equations.selection",
}


def _imports(path: Path) -> set[str]:
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
    return found


@pytest.mark.parametrize("name", MODULES)
def test_modules_import_only_numpy_numba_and_one_another(name: str) -> None:
    path = EQUATIONS / f"{name}.py"
    outside = {
        m
        for m in _imports(path)
        if m.partition(".")[0] not in sys.stdlib_module_names
        and m.partition(".")[0] not in ALLOWED
        and m not in ALLOWED
        and not m.startswith("hcomc.equations")
    }
    assert outside == set()
    assert len(path.read_text(encoding="utf-8").splitlines()) <= 400


@pytest.mark.parametrize("name", PUBLIC)
def test_public_functions_are_documented_with_units_and_their_source(name: str) -> None:
    module = importlib.import_module(f"hcomc.equations.{name}")
    assert "arXiv:2507.11621" in (module.__doc__ or ""), "the module cites the paper"
    for attr in module.__all__:
        obj = getattr(module, attr)
        func = getattr(obj, "py_func", obj)
        if not inspect.isfunction(func):
            continue
        doc = inspect.getdoc(func) or ""
        for section in ("Parameters", "Returns"):
            assert section in doc, f"{name}.{attr}: no {section} section"
        assert "[" in doc, f"{name}.{attr}: no units"


@pytest.mark.parametrize(("old", "new"), sorted(MOVED.items()))
def test_old_homes_re_export_the_same_objects(old: str, new: str) -> None:
    before, after = importlib.import_module(old), importlib.import_module(new)
    shared = [n for n in getattr(before, "__all__", ()) if hasattr(after, n)]
    assert shared
    for name in shared:
        assert getattr(before, name) is getattr(after, name), f"{old}.{name}"


def test_stopping_distance() -> None:
    assert stopping_distance(20.0, 4.0, 2.0) == 20.0 * 20.0 / 8.0 + 2.0
    assert stopping_distance(0.0, 4.0, 2.0) == 2.0
