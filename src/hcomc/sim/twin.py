"""The undisturbed twin of a run, made from the run's own state instead of simulated again.

The undisturbed run (``Simulation(config, seed, counterfactual=True)``) has the same demand
and random streams but never releases ramp vehicles. Until a ramp vehicle reaches the
acceleration lane it cannot interact with mainline traffic: no mainline vehicle has it as a
leader, changes lanes onto the ramp or collides with it, and the perception errors of every
driver do not depend on who is on the road. Up to that moment the undisturbed run therefore
*is* the run without its ramp vehicles, and :func:`undisturbed_twin` builds it that way: the
state, the random generator and the log copied, the ramp vehicles' columns and events left
out. Learning environments use it to start each episode's reference run at the cost of a
copy; a test checks that the twin and the simulated undisturbed run agree bit for bit to the
end of the run.

The same argument lets an environment put off making the twin: while :func:`can_twin` holds,
the undisturbed run's mainline *is* the run's own, log rows included.
:func:`~hcomc.sim.step.ramp_reach.ramp_may_reach` says when that may end within the next
stretch of time, and :func:`~hcomc.sim.step.ramp_reach.ramp_untouched` checks afterwards that
it did not.
"""

from __future__ import annotations

import numpy as np

from hcomc.road import Lane
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.log.layout import CELL_FIELDS, FILL
from hcomc.sim.log.slots import OPEN
from hcomc.sim.step import state as layout
from hcomc.sim.step.build import adopt_log_columns
from hcomc.sim.step.ramp_reach import ramp_untouched

# the state arrays a step changes (everything else is built from config and demand alike)
_STATE = (
    "x", "y", "v", "a", "heading", "lane", "origin", "target", "lc_t0", "lc_x0", "lc_xf",
    "lc_dur", "active", "waited", "identified", "planned", "a_cmd", "held", "route", "x_hist",
    "v_hist", "w_gap", "w_ttc", "queue_pos", "colliding", "counters", "innov",
)  # fmt: skip
_PER_VEHICLE = (
    "x", "y", "v", "a", "heading", "lane", "origin", "target", "lc_t0", "lc_x0", "lc_xf",
    "lc_dur", "active", "waited", "identified", "planned", "a_cmd", "held", "route", "w_gap",
    "w_ttc",
)  # fmt: skip


def _copy_log_without(src: SimulationLog, dst: SimulationLog, rows: int, gone: np.ndarray) -> None:
    """Copy the first ``rows`` rows of ``src`` into the empty ``dst`` (with its slot tables),
    leaving the vehicles ``gone`` out: their cells back to the fill, their slots free."""
    dst.grow_slots(src.n_slots)
    dst.t[:rows] = src.t[:rows]
    for name in CELL_FIELDS:
        dst.cells[name][:rows, : src.n_slots] = src.cells[name][:rows]
    np.copyto(dst.slot, src.slot)
    np.copyto(dst.span, src.span)
    dst.owner[: src.n_slots] = src.owner
    for i in gone[src.slot[gone] >= 0].tolist():
        s, (first, end) = dst.slot[i], dst.span[i]
        for name in CELL_FIELDS:
            dst.cells[name][first : min(end, rows), s] = FILL[name]
        if end == OPEN:
            dst.owner[s] = -1
        dst.slot[i], dst.span[i] = -1, 0


def can_twin(sim: Simulation) -> bool:
    """Whether ``sim``'s undisturbed run can be made from its state now: no plan, and every
    ramp vehicle released so far still on the ramp before the acceleration lane, keeping its
    lane, in no collision."""
    if sim.counterfactual or sim.plans or sim.decisions or sim.finished:
        return False
    if not ramp_untouched(sim.core):
        return False
    sim.flush_events()  # the collision events below must be in the log
    ramp = sim.demand.lane == Lane.RAMP
    return not _involving(sim.log.events_of(EventKind.COLLISION), ramp).any()


def _marked(ids: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Which of the vehicle ids (-1: none) the boolean mask over vehicles marks."""
    return (ids >= 0) & mask[np.maximum(ids, 0)]


def _involving(events: np.ndarray, vehicles: np.ndarray) -> np.ndarray:
    """Which ``events`` name a vehicle the mask ``vehicles`` marks, as either party."""
    return _marked(events["vehicle"], vehicles) | _marked(events["other"], vehicles)


def undisturbed_twin(sim: Simulation) -> Simulation:
    """The undisturbed run of ``sim``'s scenario and seed, at ``sim``'s step (see the module
    doc); raises ``ValueError`` when :func:`can_twin` says it cannot be made."""
    if not can_twin(sim):
        raise ValueError("the undisturbed twin cannot be copied now: a ramp vehicle already "
                         "interacts with the mainline (or a plan exists)")  # fmt: skip
    twin = Simulation._sibling(sim, counterfactual=True)  # the same demand, not drawn again
    src, dst = sim.arrays, twin.arrays
    is_ramp = sim.demand.lane == Lane.RAMP
    ramp = np.flatnonzero(is_ramp)
    kept = {name: getattr(dst, name)[ramp].copy() for name in _PER_VEHICLE}
    hist = (dst.x_hist[:, ramp].copy(), dst.v_hist[:, ramp].copy())
    ramp_queue = int(dst.queue_pos[Lane.RAMP])
    for name in _STATE:
        np.copyto(getattr(dst, name), getattr(src, name))
    for name, values in kept.items():
        getattr(dst, name)[ramp] = values
    dst.x_hist[:, ramp], dst.v_hist[:, ramp] = hist
    dst.queue_pos[Lane.RAMP] = ramp_queue
    dst.counters[layout.N_KEYS] = 0  # the key groups found so far are the ramp vehicles'
    events = sim.log.events_since(0)
    inserted = events[(events["kind"] == EventKind.INSERTION) & _marked(events["vehicle"], is_ramp)]
    steps = np.round((inserted["t"] + sim.config.warmup) / sim.dt).astype(np.int64)
    dst.counters[layout.VEHICLE_STEPS] -= int((sim.step_index - steps).sum())
    twin.rng.bit_generator.state = sim.rng.bit_generator.state
    _copy_log_without(sim.log, twin.log, sim.rows_recorded, ramp)
    twin.arrays = adopt_log_columns(twin.arrays, twin.core, twin.log)
    twin.log.add_events(events[~_involving(events, is_ramp)])
    twin._stage = sim._stage
    return twin


__all__ = ["can_twin", "undisturbed_twin"]
