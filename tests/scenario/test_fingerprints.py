"""The same numbers on every machine: the reference runs equal, bit for bit, their digests
recorded in ``tests/data/fingerprints.json``, and numpy's CPU-dispatched code paths do not
change them.

The 60 reference runs (``benchmarks/fingerprint.py``: C1-C5 with no controller, FIFO, Game
and HCOMC with NSGA-II, PSO and SA, seeds 0 and 1) digest the float64 end state, the logged
trajectories and the events. A host on which any number differs fails here, whatever its
processor. The recording's host is named in the file; ``python benchmarks/fingerprint.py
--json`` prints the digests anew after a change that is meant to change numbers.

numpy picks SIMD versions of its functions by the processor it runs on (e.g. AVX-512 ones of
``exp``, ``log`` and ``power``, whose last bit differs from the C library's, and an AVX-512
sort that orders ties its own way). The last test runs the 60 runs again with every
dispatchable numpy feature of this processor disabled (``NPY_DISABLE_CPU_FEATURES``: numpy's
baseline code, as on a processor without them) and requires the same digests: no result
depends on numpy's dispatch.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]
RECORDED = ROOT / "tests" / "data" / "fingerprints.json"
SCRIPT = ROOT / "benchmarks" / "fingerprint.py"


def _script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("hcomc_fingerprint", SCRIPT)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _recorded() -> dict[str, str]:
    digests = json.loads(RECORDED.read_text(encoding="utf-8"))["digests"]
    assert isinstance(digests, dict)
    return digests


def test_the_recording_covers_every_reference_run() -> None:
    names = [name for name, *_ in _script().cases()]
    assert len(names) == 60
    assert sorted(_recorded()) == sorted(names)


@pytest.mark.parametrize("name", [name for name, *_ in _script().cases()])
def test_a_reference_run_equals_its_recorded_digest(name: str) -> None:
    script = _script()
    found = {n: (c, ctl, seed) for n, c, ctl, seed in script.cases()}
    assert script.digest(*found[name]) == _recorded()[name]


def _dispatched_features() -> list[str]:
    """numpy's dispatchable features this processor has (empty on a baseline-only one)."""
    from numpy._core._multiarray_umath import (  # type: ignore[attr-defined]
        __cpu_dispatch__,
        __cpu_features__,
    )

    return [name for name in __cpu_dispatch__ if __cpu_features__.get(name)]


def test_the_runs_do_not_depend_on_numpys_cpu_dispatch() -> None:
    features = _dispatched_features()
    env = {**os.environ, "NPY_DISABLE_CPU_FEATURES": " ".join(features)}
    command = [sys.executable, str(SCRIPT), "--json"]
    done = subprocess.run(
        command, env=env, capture_output=True, text=True, timeout=1800, check=False
    )
    assert done.returncode == 0, done.stderr[-3000:]
    digests = json.loads(done.stdout)
    del digests["all"]
    assert digests == _recorded()
