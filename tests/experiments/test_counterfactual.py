"""The undisturbed counterfactual (no ramp vehicle released) shares every random stream with
the factual run, so the vehicles the merge cannot reach move bit-identically."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.metrics import compute_metrics, key_window
from hcomc.sim.engine import Simulation
from hcomc.sim.log import SimulationLog


def _same(a: SimulationLog, b: SimulationLog, rows: slice, cols: np.ndarray | slice) -> bool:
    return all(
        np.array_equal(getattr(a, name)[rows][:, cols], getattr(b, name)[rows][:, cols], True)
        for name in ("x", "v", "a", "lane", "active")
    )


@pytest.mark.parametrize(
    ("condition", "seed", "controller"),
    [(c, s, "none") for c in ("C1", "C2", "C3", "C4", "C5") for s in (0, 1)]
    + [("C5", 1, "fifo"), ("C5", 1, "game"), ("C5", 1, "hcomc")],
)
def test_counterfactual_differs_only_where_the_merge_reaches(
    condition: str, seed: int, controller: str
) -> None:
    """Planning draws no number from the run's stream, so controllers keep this too."""
    config = load_config(condition, control={"controller": controller})
    factual = Simulation(config, seed)
    f_log = factual.run()
    counter = Simulation(config, seed, counterfactual=True)
    c_log = counter.run()
    assert counter.key_groups == {}  # nothing merges in the counterfactual
    vr, group = next(iter(factual.key_groups.items()))
    n = f_log.n_recorded
    released = int(np.argmax(f_log.active[:n, vr]))
    assert released > 0
    # before VR is on the road every vehicle is identical
    assert _same(f_log, c_log, slice(0, released), slice(None))
    assert not c_log.active[:n, vr].any()
    # vehicles ahead of every key vehicle when VR enters the control zone are never touched
    # (IDM/ACC leaders do not react to followers), HDVs included: their estimation errors
    # do not depend on whether VR's column is drawn for
    entry = int(np.searchsorted(f_log.t[:n], factual.log.meta["key_groups"][0]["t"] - 1e-9))
    keys = np.array([i for i in group.as_dict().values() if i >= 0])
    x_entry = f_log.x[entry].astype(float)
    front = np.nanmax(x_entry[keys])
    ahead = np.flatnonzero(f_log.active[entry] & (x_entry > front + 1.0))
    assert ahead.size > 0
    assert _same(f_log, c_log, slice(0, n), ahead)
    # and the merge does disturb somebody (the test can fail)
    others = np.setdiff1d(np.arange(f_log.x.shape[1]), [vr])
    assert not _same(f_log, c_log, slice(0, n), others)


def _pair(condition: str, seed: int, **overrides: object) -> tuple[SimulationLog, SimulationLog]:
    config = load_config(condition, **overrides)
    return (
        Simulation(config, seed).run(),
        Simulation(config, seed, counterfactual=True).run(),
    )


def test_run_without_ramp_vehicle_scores_no_disturbance() -> None:
    log, reference = _pair("C5", 3, duration=40.0, demand={"ramp": "none"})
    values = compute_metrics(log, reference=reference)
    assert values["stabilisation_time"] <= 1.0
    assert values["average_acceleration"] == pytest.approx(0.0, abs=1e-12)
    assert values["lsrv"] == pytest.approx(0.0, abs=1e-9)


def test_factual_equal_to_counterfactual_scores_no_disturbance() -> None:
    log, reference = _pair("C1", 0)
    window = key_window(log)  # the merge's window and key vehicles, applied to the no-merge run
    assert window.merged
    values = compute_metrics(reference, window, reference=reference)
    assert values["stabilisation_time"] <= 1.0
    assert values["average_acceleration"] == 0.0
    assert values["lsrv"] == 0.0
    merged = compute_metrics(log, reference=reference)  # the merge itself does disturb
    assert merged["lsrv"] > 100.0
    assert merged["average_acceleration"] > 0.005
    assert merged["stabilisation_time"] > 2.0
