"""Runs the CommonRoad export tests read: a short C2 run whose merging vehicle VR enters at
1 s, and a short corridor-engine run with sampled trajectories (written once per session)."""

from __future__ import annotations

import warnings
from contextlib import suppress
from pathlib import Path

import pytest
from commonroad_cli import invoke

C2_SETTINGS = ["--duration", "25", "--set", "demand.ramp_entry_time=1.0"]
"""25 s of C2 with VR released 1 s after the warm-up: VR enters (row 11), changes lane from
about 18 s on and has merged before the end."""

with warnings.catch_warnings(), suppress(ImportError):  # without the extra the tests skip
    warnings.simplefilter("ignore", DeprecationWarning)  # commonroad-io's protobuf modules
    import commonroad.common.file_reader  # noqa: F401  # warn on import, harmlessly


@pytest.fixture(scope="session")
def c2_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``hcomc simulate C2 ... --out DIR``: the run's directory."""
    out = tmp_path_factory.mktemp("c2") / "run"
    code, output = invoke("simulate", "C2", *C2_SETTINGS, "--out", str(out), "--json")
    assert code == 0, output
    return out


@pytest.fixture(scope="session")
def corridor_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``hcomc simulate corridor --duration 40 --trajectory-interval 0.5 --out DIR``."""
    out = tmp_path_factory.mktemp("corridor") / "run"
    code, output = invoke("simulate", "corridor", "--duration", "40", "--trajectory-interval",
                          "0.5", "--out", str(out), "--json")  # fmt: skip
    assert code == 0, output
    return out
