"""Each kernel's cache is keyed on its own module and what that imports (hcomc._stamp), so an
edit recompiles only the kernels that depend on the edited module.

The edits are made to a copy of the package in a temporary directory; nothing is compiled."""

from __future__ import annotations

import shutil
import textwrap
from collections.abc import Callable
from pathlib import Path

import pytest

from hcomc import _stamp
from hcomc._jit import PACKAGE

CAR_FOLLOWING = (
    "equations/car_following.py"
    if (PACKAGE / "equations" / "car_following.py").exists()
    else "models/idm.py"
)
"""The module of Eq. 1 (IDM), the root of most kernels' imports."""


@pytest.fixture
def package(tmp_path: Path) -> Path:
    """A copy of the hcomc package's sources."""
    copy = tmp_path / "hcomc"
    shutil.copytree(PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    return copy


def _stamps(package: Path) -> dict[str, str]:
    """The stamp of every kernel module of ``package``, read afresh."""
    _stamp.forget_sources()
    return {name: _stamp.module_stamp(name, package) for name in _stamp.kernel_modules(package)}


def _edited(package: Path, relative: str, edit: Callable[[str], str]) -> dict[str, str]:
    path = package / relative
    path.write_text(edit(path.read_text(encoding="utf-8")), encoding="utf-8")
    return _stamps(package)


def _comment(text: str) -> str:
    return text + "\n# an edit\n"


def test_the_package_has_kernels_in_many_modules(package: Path) -> None:
    stamps = _stamps(package)
    assert len(stamps) >= 40
    assert "hcomc.sim.step.motion" in stamps
    assert len(set(stamps.values())) == len(stamps)  # each module its own stamp


@pytest.mark.parametrize(
    "relative",
    ["experiments/runner.py", "cli/_app.py", "cli/compare.py", "config/schema.py", "viz/common.py"],
)
def test_an_edit_of_a_module_no_kernel_imports_leaves_every_stamp(
    package: Path, relative: str
) -> None:
    before = _stamps(package)
    assert _edited(package, relative, _comment) == before


def test_no_kernel_depends_on_the_command_line_or_the_experiments(package: Path) -> None:
    _stamps(package)
    for name in _stamp.kernel_modules(package):
        outside = [
            m
            for m in _stamp.closure(name, package)
            if m.split(".")[1] in {"cli", "experiments", "viz", "config", "robustness", "sumo"}
        ]
        assert outside == [], name


def test_an_edit_of_car_following_restamps_exactly_the_kernels_that_import_it(
    package: Path,
) -> None:
    before = _stamps(package)
    edited = _stamp.module_name(package / CAR_FOLLOWING, package)
    importers = {n for n in before if edited in _stamp.closure(n, package)}
    after = _edited(package, CAR_FOLLOWING, _comment)
    changed = {name for name in before if before[name] != after[name]}
    assert changed == importers
    assert "hcomc.sim.step.motion" in changed  # the step follows the leader by Eq. 1
    assert changed < set(before)  # not everything: e.g. the optimisers' operators
    assert "hcomc.optim.dominance" not in changed


def test_a_stamp_follows_imports_through_modules_without_kernels(package: Path) -> None:
    """A kernel module that imports a plain module, which imports another: an edit of the
    last restamps the first."""
    (package / "chain_a.py").write_text(
        "from hcomc._jit import kernel\nfrom hcomc import chain_b\n"
    )
    (package / "chain_b.py").write_text("from hcomc.chain_c import VALUE\n")
    (package / "chain_c.py").write_text("VALUE = 1.0\n")
    before = _stamps(package)
    assert _stamp.closure("hcomc.chain_a", package) == [
        "hcomc._jit",
        "hcomc.chain_a",
        "hcomc.chain_b",
        "hcomc.chain_c",
    ]
    after = _edited(package, "chain_c.py", lambda _: "VALUE = 2.0\n")
    assert after["hcomc.chain_a"] != before["hcomc.chain_a"]


def test_lazy_and_annotation_imports_are_not_followed(package: Path) -> None:
    """Compiled code cannot reach what a module imports inside a function or for annotations
    only; relative imports are made absolute."""
    (package / "sub").mkdir()
    (package / "sub" / "__init__.py").write_text("")
    (package / "sub" / "leaf.py").write_text("X = 1\n")
    source = textwrap.dedent(
        """
        from typing import TYPE_CHECKING
        from hcomc._jit import kernel
        from . import leaf
        if TYPE_CHECKING:
            from hcomc.config import ScenarioConfig
        else:
            from hcomc.road import Lane
        def f():
            from hcomc.experiments import runner
        """
    )
    (package / "sub" / "mod.py").write_text(source)
    _stamps(package)
    imports = _stamp.top_level_imports(package / "sub" / "mod.py", package)
    assert imports == {"hcomc._jit", "hcomc.sub.leaf", "hcomc.road"}
    assert "hcomc.sub.mod" in _stamp.kernel_modules(package)
