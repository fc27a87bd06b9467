"""What compiling hcomc's kernels costs: a cold compile, and the wait after an edit.

In a copy of a checkout's ``src/`` and ``tests/`` in a temporary directory (its own numba
cache beside the copied sources, so the checkout's cache is neither used nor touched):

1. **cold compile**: every compilation stage of ``hcomc.cli._compile`` from an empty cache, in
   one process (numba compiles on one core), wall and CPU seconds;
2. **edit of a module no kernel imports** (a comment appended to
   ``hcomc/experiments/runner.py``), then ``pytest tests/unit/<one model>`` until its result;
3. **edit of one leaf kernel module** (a comment appended to the car-following equation's
   module), then the same test.

Run it on a quiet machine::

    python benchmarks/compile_time.py --json
    python benchmarks/compile_time.py --checkout <checkout of an earlier revision> --json

(an earlier revision whose ``ensure_compiled`` takes no stages compiles all of its stages).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TEST = "tests/unit/test_idm.py"
NON_KERNEL = "hcomc/experiments/runner.py"
LEAF_KERNELS = ("hcomc/equations/idm.py", "hcomc/models/idm.py")  # the first that exists

_COLD = """
import inspect
from rich.console import Console
from hcomc.cli import _compile
console = Console(stderr=True)
if "stages" in inspect.signature(_compile.ensure_compiled).parameters:
    _compile.ensure_compiled(console, tuple(_compile.STAGES))
else:
    _compile.ensure_compiled(console)
"""


def _copy(checkout: Path, into: Path) -> Path:
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info")
    for part in ("src", "tests"):
        shutil.copytree(checkout / part, into / part, ignore=ignore)
    shutil.copy2(checkout / "pyproject.toml", into / "pyproject.toml")
    return into


def _timed(command: list[str], cwd: Path) -> dict[str, float]:
    """Wall and CPU seconds (children's user + system) of ``command``."""
    env = {**os.environ, "PYTHONPATH": str(cwd / "src")}
    env.pop("NUMBA_CACHE_DIR", None)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed:\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": round(wall, 1), "cpu_s": round(cpu, 1)}


def _append_comment(path: Path) -> None:
    path.write_text(path.read_text(encoding="utf-8") + "\n# an edit\n", encoding="utf-8")


def measure(checkout: Path, cold_only: bool) -> dict[str, object]:
    with tempfile.TemporaryDirectory(prefix="hcomc-compile-") as tmp:
        copy = _copy(checkout, Path(tmp))
        test = [sys.executable, "-m", "pytest", TEST, "-q", "-x", "-p", "no:cacheprovider"]
        result: dict[str, object] = {"cold_compile": _timed([sys.executable, "-c", _COLD], copy)}
        result["first_test_after_cold_compile"] = _timed(test, copy)
        if cold_only:
            return result
        _append_comment(copy / "src" / NON_KERNEL)
        result["test_after_edit_of_non_kernel_module"] = _timed(test, copy)
        leaf = next(name for name in LEAF_KERNELS if (copy / "src" / name).exists())
        _append_comment(copy / "src" / leaf)
        result["test_after_edit_of_leaf_kernel_module"] = _timed(test, copy)
        result["leaf_kernel_module"] = leaf
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkout", type=Path, default=ROOT, help="checkout to measure")
    parser.add_argument("--json", action="store_true", help="one JSON object")
    parser.add_argument("--cold-only", action="store_true", help="skip the two edits")
    args = parser.parse_args()
    result = {
        "checkout": str(args.checkout),
        "machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count()},
        **measure(args.checkout.resolve(), args.cold_only),
    }
    print(json.dumps(result, indent=1) if args.json else result)


if __name__ == "__main__":
    main()
