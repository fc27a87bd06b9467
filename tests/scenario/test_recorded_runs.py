"""The engine reproduces its recorded runs (``tests/data/engine_runs``, ``record.py`` there).

C1-C5 with no controller, FIFO, Game and HCOMC, C4 with a ramp flow and the platoon scenario,
seed 0, recorded from the engine itself: the controllers' decisions are included, so the
hand-over between Python decisions and the compiled loop is covered too. The logs (float32),
the event kinds and vehicles must be identical; float64 positions and event values within
1e-9 m, since another CPU's C library may round pow, exp or tanh differently in the last bit.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

DATA = Path(__file__).parent.parent / "data" / "engine_runs"
_spec = importlib.util.spec_from_file_location("record", DATA / "record.py")
assert _spec is not None
assert _spec.loader is not None
recorded = importlib.util.module_from_spec(_spec)  # its CASES: what was recorded
_spec.loader.exec_module(recorded)


def test_every_case_is_recorded_and_stamped() -> None:
    assert {p.stem for p in DATA.glob("*.npz")} == set(recorded.CASES)
    stamp = json.loads((DATA / "recorded.json").read_text(encoding="utf-8"))
    assert len(stamp["revision"]) == 40
    assert stamp["seed"] == 0


@pytest.mark.parametrize("name", sorted(recorded.CASES))
def test_the_engine_reproduces_its_recorded_run(name: str) -> None:
    ref = np.load(DATA / f"{name}.npz")
    got = recorded.run(*recorded.CASES[name])
    np.testing.assert_allclose(got["x"], ref["x"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(got["v"], ref["v"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(got["y"], ref["y"], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(got["lane"], ref["lane"])
    np.testing.assert_array_equal(got["log_x"], ref["log_x"])
    np.testing.assert_array_equal(got["log_v"], ref["log_v"])
    events = got["events"]
    np.testing.assert_array_equal(events[:, :4], ref["events"][:, :4])  # t, kind, vehicles
    np.testing.assert_allclose(events[:, 4:], ref["events"][:, 4:], rtol=0, atol=1e-9)
