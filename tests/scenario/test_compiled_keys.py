"""Key groups found in the compiled loop: a run without a controller or listeners never steps
in Python, and records the same key groups, at the same times, as the engine's Python side.

A run is made twice: as built (the compiled loop records each ramp vehicle's key group at its
control-zone entry) and with the loop's flag cleared, so that the step in which a ramp vehicle
enters the zone is taken in Python (:meth:`Simulation._identify_key_vehicles`). Both must give
the same key groups, in the same order, at the same times, and bit-identical logs.
"""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.corridor.loading import load_corridor
from hcomc.road import KEY_ROLES, VR
from hcomc.sim.corridor_scene import corridor_config, corridor_scene
from hcomc.sim.engine import Simulation
from hcomc.sim.ensemble import advance_ensemble
from hcomc.sim.log.layout import CELL_FIELDS
from hcomc.sim.step import state as layout


def _in_python(sim: Simulation) -> Simulation:
    """``sim`` with its key groups found by the engine's Python side."""
    sim.arrays.flags[layout.KEYS_COMPILED] = False
    return sim


def _same_runs(compiled: Simulation, python: Simulation) -> None:
    assert compiled.log.meta["key_groups"] == python.log.meta["key_groups"]
    assert compiled.key_groups == python.key_groups
    for name in CELL_FIELDS:
        np.testing.assert_array_equal(getattr(compiled.log, name), getattr(python.log, name))
    events = [np.asarray(run.log.events.tolist(), dtype=np.float64) for run in (compiled, python)]
    np.testing.assert_array_equal(*events)  # (as floats: NaN fields equal)
    np.testing.assert_array_equal(compiled.arrays.identified, python.arrays.identified)


@pytest.mark.parametrize("condition", ["C1", "C3", "C5"])
@pytest.mark.parametrize("seed", [0, 1])
def test_key_groups_found_compiled_are_the_python_ones(condition: str, seed: int) -> None:
    config = load_config(condition, control={"controller": "none"})
    compiled, python = Simulation(config, seed), _in_python(Simulation(config, seed))
    compiled.run()
    python.run()
    _same_runs(compiled, python)
    assert len(compiled.log.meta["key_groups"]) >= 1
    assert compiled.python_steps == 0
    assert python.python_steps == len(python.log.meta["key_groups"])


def test_a_corridor_records_the_key_groups_of_every_ramp_without_python() -> None:
    """Five on-ramps, each ramp vehicle's group with the lanes of its own ramp."""
    corridor = load_corridor("corridor", {"corridor.duration": 240.0})
    config = corridor_config(corridor, control={"controller": "none"})
    runs = [Simulation(config, 3, scene=corridor_scene(corridor)) for _ in range(2)]
    compiled, python = runs[0], _in_python(runs[1])
    compiled.run()
    python.run()
    _same_runs(compiled, python)
    groups = compiled.log.meta["key_groups"]
    assert len({int(compiled.demand.lane[g[KEY_ROLES[VR]]]) for g in groups}) == 5  # every on-ramp
    assert compiled.python_steps == 0


def test_a_run_waiting_for_key_vehicles_stops_after_the_step_that_found_them() -> None:
    """``run_to(..., until_key_vehicles=True)`` and an ensemble waiting for them stop where
    the Python side stops: after the step in which the first group was found."""
    config = load_config("C2", control={"controller": "none"})
    compiled, python = Simulation(config, 0), _in_python(Simulation(config, 0))
    end = compiled.n_warmup + compiled.n_steps
    compiled.run_to(end, until_key_vehicles=True)
    python.run_to(end, until_key_vehicles=True)
    assert compiled.step_index == python.step_index < end
    assert compiled.key_groups == python.key_groups != {}
    assert compiled.arrays.flags[layout.STOP_AT_KEYS] == 0  # cleared on return
    batch = [Simulation(config, seed) for seed in (0, 1)]
    advance_ensemble(batch, None, until_key_vehicles=[True, False], threads=1)
    assert batch[0].step_index == python.step_index
    assert batch[1].finished
    solo = _in_python(Simulation(config, 1))
    solo.run()
    _same_runs(batch[1], solo)
