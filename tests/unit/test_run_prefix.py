"""A seed's run does not depend on its duration: a shorter run is exactly the first rows and
events of a longer run of the same seed (demand, HDV estimation errors and controllers alike),
because every random stream is consumed the same way up to the shorter run's end."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from hcomc.config import HDVParams, load_config
from hcomc.rng import make_rng
from hcomc.sim.engine import Simulation
from hcomc.sim.log import SimulationLog
from hcomc.sim.log.events import EVENT_DTYPE
from hcomc.sim.perception_state import Perception

SHORT, LONG = 45.0, 50.0
SEEDS = (0, 4)  # 50 vs 52 and 48 vs 52 vehicles in C1 and C4
FIELDS = ("x", "y", "v", "a", "heading", "lane", "active")
EVENT_FIELDS = tuple(EVENT_DTYPE.fields or ())


@functools.cache
def _run(
    condition: str, controller: str, errors: bool, duration: float, seed: int = SEEDS[0]
) -> SimulationLog:
    config = load_config(
        condition, duration=duration, control={"controller": controller},
        hdv={"estimation_errors": errors},
    )  # fmt: skip
    return Simulation(config, seed).run()


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("errors", [True, False])
@pytest.mark.parametrize("controller", ["none", "fifo"])
@pytest.mark.parametrize("condition", ["C1", "C4"])
def test_shorter_run_is_the_first_rows_of_a_longer_run(
    condition: str, controller: str, errors: bool, seed: int
) -> None:
    short = _run(condition, controller, errors, SHORT, seed)
    long = _run(condition, controller, errors, LONG, seed)
    rows, n = short.n_steps, short.n_vehicles
    assert 0 < rows < long.n_steps
    assert 0 < n < long.n_vehicles  # the longer run has more vehicles
    np.testing.assert_array_equal(short.t, long.t[:rows])
    for name in FIELDS:  # every vehicle, exactly (NaN where off the road compares equal)
        np.testing.assert_array_equal(
            np.asarray(getattr(short, name)[:rows]),
            np.asarray(getattr(long, name)[:rows, :n]), err_msg=name,
        )  # fmt: skip
    np.testing.assert_array_equal(short.kind, long.kind[:n])
    assert not np.asarray(long.active[:rows, n:]).any()  # its extra vehicles come later
    assert np.asarray(short.active).any(axis=0).sum() > 10
    assert (short.events["t"] < SHORT - 1e-9).all()
    before = long.events[long.events["t"] < SHORT - 1e-9]
    for name in EVENT_FIELDS:  # field by field: NaN payloads compare equal
        np.testing.assert_array_equal(short.events[name], before[name], err_msg=name)


def test_the_errors_are_on_in_the_runs_above() -> None:
    """``hdv.estimation_errors`` is the switch the runs above turn on and off; on, the runs
    differ from the runs without errors."""
    config = load_config("C1", duration=SHORT, hdv={"estimation_errors": True})
    assert Perception(config.hdv, np.ones(4, dtype=bool), config.dt, make_rng(0)).errors
    on, off = _run("C1", "none", True, SHORT), _run("C1", "none", False, SHORT)
    assert not np.array_equal(np.asarray(on.x), np.asarray(off.x), equal_nan=True)


# ------------------------------------------------------- the perception's streams alone
_ERRORS = HDVParams(estimation_errors=True)


def test_initial_errors_of_fewer_vehicles_are_the_first_of_more() -> None:
    """w(0) of vehicle i does not depend on the number of vehicles, and the run's generator
    advances by the same fixed amount whatever that number."""
    states, perceptions = [], []
    for n in (7, 30, 500):
        rng = make_rng(9)
        perceptions.append(Perception(_ERRORS, np.ones(n, dtype=bool), 0.1, rng))
        states.append(rng.bit_generator.state)
    assert states[0] == states[1] == states[2]
    for p in perceptions[:2]:
        n = p.w_gap.size
        np.testing.assert_array_equal(p.w_gap, perceptions[2].w_gap[:n])
        np.testing.assert_array_equal(p.w_ttc, perceptions[2].w_ttc[:n])
    assert not np.array_equal(perceptions[2].w_gap, perceptions[2].w_ttc)  # two streams


def test_no_errors_draw_nothing() -> None:
    rng = make_rng(9)
    before = rng.bit_generator.state
    Perception(HDVParams(estimation_errors=False), np.ones(10, dtype=bool), 0.1, rng)
    assert rng.bit_generator.state == before


def test_error_paths_depend_on_the_vehicles_due_not_on_the_run_size() -> None:
    """A step draws (2, due) innovations for the vehicles due so far: the error paths of a run
    with 12 vehicles are those of the first 12 of a run with 40, and the generator stands at
    the same place, while the due count grows as vehicles are released."""
    due = [3] * 5 + [7] * 10 + [12] * 20

    def run(n: int) -> tuple[np.ndarray, np.ndarray, object]:
        rng = make_rng(2)
        perception = Perception(_ERRORS, np.ones(n, dtype=bool), 0.1, rng)
        for m in due:
            perception.advance_errors(np.arange(0, m, 2), rng, m)
        return perception.w_gap.copy(), perception.w_ttc.copy(), rng.bit_generator.state

    small, large = run(12), run(40)
    np.testing.assert_array_equal(small[0], large[0][:12])
    np.testing.assert_array_equal(small[1], large[1][:12])
    assert small[2] == large[2]
    with pytest.raises(ValueError, match="due"):
        Perception(_ERRORS, np.ones(5, dtype=bool), 0.1, make_rng(0)).advance_errors(
            np.array([4]), make_rng(1), 3
        )
