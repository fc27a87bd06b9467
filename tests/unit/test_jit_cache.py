"""hcomc's kernel cache follows the sources each kernel depends on (hcomc._jit,
hcomc._stamp): a cached kernel whose callee in another file changed is compiled anew, not
loaded stale, and the cache files of earlier sources are never opened."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

from hcomc._jit import PACKAGE, PackageCacheLocator, file_stamp
from hcomc._stamp import closure, forget_sources, kernel_modules

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


def test_a_stamp_covers_the_module_and_what_it_imports_and_no_other(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "params.py").write_text("SCALE = 2.0\n")  # read by a kernel, not compiled
    (pkg / "model.py").write_text(
        "from hcomc._jit import kernel\nfrom .sub import (\n    params,  # read by a kernel\n)\n"
    )
    (pkg / "cli.py").write_text("from pkg.model import X\n")  # imports a kernel file: outside
    assert closure("pkg.model", pkg) == ["pkg.model", "pkg.sub.params"]
    assert kernel_modules(pkg) == ["pkg.model"]

    def stamp() -> str:
        forget_sources()
        return file_stamp(pkg / "model.py", pkg)

    before = stamp()
    (pkg / "cli.py").write_text("from pkg.model import Y\n")
    assert stamp() == before  # the command line does not recompile
    (pkg / "sub" / "params.py").write_text("SCALE = 3.0\n")
    assert stamp() != before
    assert PackageCacheLocator.package == PACKAGE
    assert (PACKAGE / "_jit.py").exists()


def test_every_compiled_module_of_hcomc_is_stamped():
    stamped = set(kernel_modules(PACKAGE))
    for name in ("hcomc.sim.step.loop", "hcomc.control.key_vehicles", "hcomc.sim.neighbours"):
        assert name in stamped, name
    for name in ("hcomc.cli._app", "hcomc.experiments.claims", "hcomc.viz.report"):
        assert name not in stamped, name


_RUN_RECORD = """
import sys
from pathlib import Path
sys.path.insert(0, {root!r})
from hcomc._jit import PackageCacheLocator, use_package_stamp

class Locator(PackageCacheLocator):
    package = Path({root!r}) / "pkg"

use_package_stamp(Locator)
from pkg.caller import Pair, total
print(total(Pair(1.0, 2.0)))
"""


def test_a_cache_whose_types_moved_to_another_module_is_not_opened(tmp_path):
    """numba unpickles a cache index (with the types of its signatures, which name their
    modules) before it compares the index's stamp: the cache files of other sources have
    other names, so a record type that moved to another module cannot break the load; the
    files of the earlier sources are then removed."""
    from hcomc._jit import TAG_LENGTH, remove_stale_caches

    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    record = """
        from typing import NamedTuple

        class Pair(NamedTuple):
            a: float
            b: float
        """
    caller = """
        from hcomc._jit import kernel
        from pkg.{module} import Pair

        @kernel
        def total(p):
            return p.a + p.b
        """

    def run() -> str:
        script = _RUN_RECORD.format(root=str(tmp_path))
        argv = [sys.executable, "-c", script]
        done = subprocess.run(argv, capture_output=True, text=True, check=False, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        return done.stdout.strip()

    _write(pkg / "records.py", record)
    _write(pkg / "caller.py", caller.format(module="records"))
    assert run() == "3.0"
    first = {p.name for p in (pkg / "__pycache__").glob("caller.total-*")}
    assert first
    (pkg / "records.py").rename(pkg / "shapes.py")
    _write(pkg / "caller.py", caller.format(module="shapes"))
    assert run() == "3.0"  # numba alone: ModuleNotFoundError: No module named 'pkg.records'
    forget_sources()
    fresh = file_stamp(pkg / "caller.py", pkg)[:TAG_LENGTH]
    assert all(fresh not in name for name in first)
    assert remove_stale_caches(pkg) == len(first)
    left = {p.name for p in (pkg / "__pycache__").glob("caller.total-*")}
    assert left
    assert all(f"-{fresh}." in name for name in left)
