"""The house style is part of the test suite: ruff's lint rules and formatting, and mypy's
type check of src/ (configuration in pyproject.toml)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TREES = ["src", "tests", "benchmarks", "examples"]


def _ruff(*args: str) -> subprocess.CompletedProcess[str]:
    """Run ruff without its cache: a cached verdict outlives a change elsewhere in the tree
    (a new directory under tests/ can make an import first-party), so only a fresh run sees
    what a clean checkout sees."""
    exe = shutil.which("ruff")
    cmd = [exe] if exe else [sys.executable, "-m", "ruff"]
    return subprocess.run(
        [*cmd, *args, "--no-cache", *TREES], cwd=ROOT, capture_output=True, text=True, check=False
    )


@pytest.mark.parametrize("args", [("check",), ("format", "--check")])
def test_ruff_is_clean(args: tuple[str, ...]) -> None:
    done = _ruff(*args)
    assert done.returncode == 0, done.stdout + done.stderr


def test_mypy_is_clean() -> None:
    """``mypy`` (with the pydantic plugin, see [tool.mypy]) finds no error in src/."""
    exe = shutil.which("mypy")
    cmd = [exe] if exe else [sys.executable, "-m", "mypy"]
    done = subprocess.run([*cmd, "src"], cwd=ROOT, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stdout + done.stderr


MAX_MODULE_LINES = 400


def test_every_module_is_at_most_400_lines() -> None:
    """A module per concept: a source file that outgrows this holds more than one."""
    long = {
        str(path.relative_to(ROOT)): n
        for path in sorted((ROOT / "src").rglob("*.py"))
        if (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES
    }
    assert not long, long
