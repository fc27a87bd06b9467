"""The undisturbed twin copied from a run equals the simulated undisturbed run, bit for bit,
to the end of the run."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.sim.engine import Simulation
from hcomc.sim.twin import can_twin, undisturbed_twin

END = 10**12
FIELDS = ("t", "x", "y", "v", "a", "heading", "lane", "active")


@pytest.mark.parametrize(("condition", "seed", "ramp"), [("C1", 0, "single"), ("C2", 3, "single"),
                                                          ("C4", 1, "flow")])  # fmt: skip
def test_twin_equals_the_simulated_undisturbed_run(condition: str, seed: int, ramp: str) -> None:
    config = load_config(condition, control={"controller": "none"}, demand={"ramp": ramp})
    sim = Simulation(config, seed)
    sim.run_to(END, until_key_vehicles=True)
    assert can_twin(sim)
    twin = undisturbed_twin(sim)
    simulated = Simulation(config, seed, counterfactual=True)
    simulated.run_to(sim.step_index)
    for name in ("x", "v", "a", "lane", "active", "x_hist", "w_gap", "counters", "queue_pos"):
        np.testing.assert_array_equal(getattr(twin.arrays, name),
                                      getattr(simulated.arrays, name), err_msg=name)  # fmt: skip
    a, b = twin.run(), simulated.run()
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for name in a.events.dtype.names:  # field by field: NaN payloads compare equal
        np.testing.assert_array_equal(a.events[name], b.events[name], err_msg=name)
    assert a.meta["vehicle_steps"] == b.meta["vehicle_steps"]


def test_no_twin_once_the_ramp_vehicle_reaches_the_acceleration_lane() -> None:
    sim = Simulation(load_config("C1", control={"controller": "none"}), 0)
    sim.run_to(END, until_key_vehicles=True)
    vr = sim.key_group.vr
    while sim.x[vr] < sim.config.road.accel_lane_start:
        sim.run_to(sim.step_index + 5)
    assert not can_twin(sim)
    with pytest.raises(ValueError, match="cannot be copied"):
        undisturbed_twin(sim)
    planned = Simulation(load_config("C1", control={"controller": "fifo"}), 0)
    planned.run_to(END, until_key_vehicles=True)
    assert not can_twin(planned)  # the plan acts from the step it is made


@pytest.mark.parametrize("counterfactual", [True, False])
def test_a_run_built_on_drawn_demand_is_the_run_of_its_seed(counterfactual: bool) -> None:
    """``Simulation._sibling`` (the twin's frame: another run's demand and fleet, not drawn
    again) gives the run a new ``Simulation`` of the same seed gives, from a run that has
    already advanced."""
    config = load_config("C2", control={"controller": "none"})
    sim = Simulation(config, 5)
    sim.run_to(400)  # the source's generator has moved on: the sibling must not start there
    a = Simulation._sibling(sim, counterfactual=counterfactual).run()
    b = Simulation(config, 5, counterfactual=counterfactual).run()
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.meta["config"] == b.meta["config"]
    assert a.meta["seed"] == b.meta["seed"]
