"""The compiled simulation step over the struct-of-arrays state of one run
(:class:`hcomc.sim.core_state.Core`, fields as in :class:`~hcomc.sim.core_state.CoreArrays`).
The step is split into kernels (here, :mod:`hcomc.sim.core_motion` and
:mod:`hcomc.sim.core_lane_change`) that the engine composes in two ways:

* :func:`run_steps` advances many steps in one compiled call while nothing needs Python:
  no live merge plan, no ramp vehicle entering the control zone, no game-confirmed lane
  change; it writes log rows and events itself;
* at a decision event the engine runs the same kernels one step at a time
  (:func:`release`, :func:`step_accelerations`, :func:`start_lane_changes`,
  :func:`step_finish`) with the controller's inputs in between.

Each equation is called from its one home (:mod:`hcomc.models`, :mod:`hcomc.safety`,
:mod:`hcomc.sim.perception`, :mod:`hcomc.sim.mobil`, :mod:`hcomc.sim.neighbours`). Semantics
(order of operations, who sees whom, events) are those documented in
:mod:`hcomc.sim.engine`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hcomc.sim.core_lane_change import (
    commanded_changes,
    discretionary_changes,
    start_lane_changes,
)
from hcomc.sim.core_motion import (
    bookkeeping,
    check_collisions,
    follow_many,
    integrate,
    lateral,
    release,
    step_accelerations,
)
from hcomc.sim.core_state import (
    CAV_GAME,
    CONTROLLER,
    CZ_START,
    DECAY,
    DECIDE_EVERY,
    DONE,
    DT,
    ERRORS,
    FLUSH,
    GROW_LOG,
    HAS_PLANS,
    INNOV_CURSOR,
    KICK,
    LOG_EVERY,
    N_EVENTS,
    N_WARMUP,
    NEED_PYTHON,
    PLATOON,
    RAMP,
    ROWS,
    STEP,
    VEHICLE_STEPS,
    WARMUP,
    CoreArrays,
    push_history,
)
from hcomc.sim.log_slots import claim_slots
from hcomc.sim.perception import advance_errors_of
from hcomc.sim.small import nonzero

__all__ = [
    "commanded_changes", "discretionary_changes", "follow_many", "push_history", "record_row",
    "release", "run_steps", "start_lane_changes", "step_accelerations", "step_finish",
]  # fmt: skip


@njit(cache=True)
def step_finish(
    c: CoreArrays, ids: np.ndarray, t: float, acc: np.ndarray, vs: np.ndarray, ls: np.ndarray
) -> None:
    """Collisions, integration, lateral motion, exits, the HDVs' error processes (one row of
    pre-drawn innovations per step with active vehicles) and the perception history."""
    check_collisions(c, t, vs, ls)
    integrate(c, ids, acc)
    lateral(c, t)
    bookkeeping(c, ids, t)
    if c.flags[ERRORS] > 0:
        hdv = ids[nonzero(c.is_hdv[ids])]
        xi = c.innov[c.counters[INNOV_CURSOR]]
        c.counters[INNOV_CURSOR] += 1
        advance_errors_of(c.w_gap, c.w_ttc, hdv, xi, c.consts[DECAY], c.consts[KICK])
    push_history(c)


# --------------------------------------------------------------------------- record
@njit(cache=True)
def record_row(c: CoreArrays, k: int, t: float) -> bool:
    """Write log row k for the vehicles on the road, each in its slot column
    (:func:`hcomc.sim.log_slots.claim_slots`); the other cells keep the log's fill (NaN,
    lane -1, inactive), so a row costs what is on the road. False, writing nothing, when the
    log needs more columns first."""
    if not claim_slots(c.active, c.log_slot, c.log_span, c.log_owner, k):
        return False
    c.log_t[k] = t
    for i in range(c.x.size):
        if c.active[i]:
            s = c.log_slot[i]
            c.log_active[k, s] = True
            c.log_x[k, s], c.log_y[k, s], c.log_v[k, s] = c.x[i], c.y[i], c.v[i]
            c.log_a[k, s], c.log_heading[k, s], c.log_lane[k, s] = c.a[i], c.heading[i], c.lane[i]
    return True


# ----------------------------------------------------------------------------- loop
@njit(cache=True)
def needs_python(c: CoreArrays) -> bool:
    """Whether this step needs the engine's Python side: a live plan, game-confirmed lane
    changes, or a ramp vehicle entering the control zone (key vehicles, a plan)."""
    if c.flags[HAS_PLANS] > 0 or c.flags[CAV_GAME] > 0:
        return True
    for i in range(c.x.size):
        if (
            c.active[i]
            and c.lane[i] == RAMP
            and c.origin[i] == c.target[i]
            and c.x[i] >= c.consts[CZ_START]
            and (not c.identified[i] or (c.flags[CONTROLLER] > 0 and not c.planned[i]))
        ):
            return True  # fmt: skip
    return False


@njit(cache=True)
def step_alone(c: CoreArrays, t: float) -> None:
    """One whole step after release with no controller inputs (the fast path)."""
    ids = nonzero(c.active)
    if ids.size == 0:
        push_history(c)
        return
    c.counters[VEHICLE_STEPS] += ids.size
    no_int = np.empty(0, dtype=np.int64)
    no_float = np.empty(0)
    no_plan = np.zeros(c.x.size, dtype=np.bool_)
    acc, changing, vs, ls, ks, rank, lead = step_accelerations(
        c, ids, t, no_plan, no_int, no_float, no_float, no_float, no_float
    )
    if (c.counters[STEP] % c.flags[DECIDE_EVERY] == 0) and c.flags[PLATOON] == 0:
        chosen, target = discretionary_changes(c, ids, changing, c.held, lead, vs, ls, ks, rank)
        start_lane_changes(c, chosen, target, t, no_float)
    step_finish(c, ids, t, acc, vs, ls)


@njit(cache=True)
def run_steps(c: CoreArrays, stop: int, log_rows: bool, rng: np.random.Generator) -> int:
    """Advance until step ``stop`` or until Python is needed; returns why it stopped.

    With ``log_rows`` every ``log_every``-th step after the warm-up writes a log row. The
    HDVs' error innovations are drawn from the run's generator ``rng`` when they run out,
    exactly as the engine's Python step draws them (the same stream whichever draws).
    """
    dt, warmup = c.consts[DT], c.consts[WARMUP]
    margin = 8 * c.x.size + 64
    while c.counters[STEP] < stop:
        if c.counters[N_EVENTS] + margin > c.ev_t.size:
            return FLUSH
        if c.flags[ERRORS] > 0 and c.counters[INNOV_CURSOR] >= c.innov.shape[0]:
            c.innov[:] = rng.standard_normal(c.innov.shape)
            c.counters[INNOV_CURSOR] = 0
        t = -warmup + c.counters[STEP] * dt
        release(c, t)
        if needs_python(c):
            return NEED_PYTHON
        step_alone(c, t)
        k = c.counters[STEP] - c.flags[N_WARMUP]
        if log_rows and k > 0 and k % c.flags[LOG_EVERY] == 0:
            t_row = -warmup + c.counters[STEP] * dt
            if not record_row(c, c.counters[ROWS], t_row):
                return GROW_LOG  # the row is written once the log has grown
            c.counters[ROWS] += 1
    return DONE
