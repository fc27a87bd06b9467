"""hcomc's kernel cache follows every source file of the package (hcomc._jit): a cached
kernel whose callee in another file changed is compiled anew, not loaded stale."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

from hcomc._jit import PACKAGE, PackageCacheLocator, source_stamp

_RUN = """
import sys
from pathlib import Path
sys.path.insert(0, {root!r})
from hcomc._jit import PackageCacheLocator, kernel, use_package_stamp

class Locator(PackageCacheLocator):
    package = Path({root!r}) / "pkg"

use_package_stamp(Locator)
from pkg.caller import twice
print(twice(1.0))
"""


def _write(path: Path, text: str) -> None:
    path.write_text(textwrap.dedent(text))


def _run(root: Path) -> str:
    return _process(root).stdout.strip()


def _process(root: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", _RUN.format(root=str(root))],
        capture_output=True, text=True, check=True, timeout=600,
    )  # fmt: skip


def test_a_kernel_is_compiled_anew_when_a_callee_in_another_file_changes(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    _write(
        pkg / "callee.py",
        """
        from hcomc._jit import kernel

        @kernel
        def model(x):
            return x + 1.0
        """,
    )
    _write(
        pkg / "caller.py",
        """
        from hcomc._jit import kernel
        from pkg.callee import model

        @kernel
        def twice(x):
            return 2.0 * model(x)
        """,
    )
    assert _run(tmp_path) == "4.0"
    assert list((pkg / "__pycache__").glob("caller.twice-*.nbi"))  # it was cached
    _write(
        pkg / "callee.py",
        """
        from hcomc._jit import kernel

        @kernel
        def model(x):
            return x + 2.0
        """,
    )
    assert _run(tmp_path) == "6.0"  # the caller's file is unchanged: numba alone says 4.0


def test_a_kernel_that_cannot_be_cached_runs_with_numbas_warning(tmp_path):
    """numba declines to cache a function that calls a ctypes function (a dynamic global) and
    warns, naming the function's file: the locator must answer numba's questions about it."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    _write(
        pkg / "caller.py",
        """
        import ctypes

        from hcomc._jit import kernel

        _fabs = ctypes.CDLL(None).fabs
        _fabs.argtypes, _fabs.restype = [ctypes.c_double], ctypes.c_double

        @kernel
        def twice(x):
            return 2.0 * _fabs(x)
        """,
    )
    out = _process(tmp_path)
    assert out.stdout.strip() == "2.0"
    assert "Cannot cache compiled function" in out.stderr
    assert str(pkg / "caller.py") in out.stderr


def test_the_stamp_covers_every_source_file_of_the_package(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "a.py").write_text("A = 1\n")
    (tmp_path / "sub" / "b.py").write_text("B = 1\n")
    before = source_stamp.__wrapped__(tmp_path)
    assert source_stamp.__wrapped__(tmp_path) == before
    (tmp_path / "sub" / "b.py").write_text("B = 2\n")
    assert source_stamp.__wrapped__(tmp_path) != before
    assert PackageCacheLocator.package == PACKAGE
    assert (PACKAGE / "_jit.py").exists()
