"""The compiled simulation step over the struct-of-arrays state of one run
(:class:`hcomc.sim.step.state.Core`, fields as in :class:`~hcomc.sim.step.state.CoreArrays`).
The step is split into kernels (here, :mod:`hcomc.sim.step.motion`,
:mod:`hcomc.sim.step.lane_change`, :mod:`hcomc.sim.step.collisions`,
:mod:`hcomc.sim.step.plans` and :mod:`hcomc.sim.step.release`), and every step of a run is
driven by one driver, :func:`run_steps`: :func:`begin_step` (event room, error innovations,
release), the vehicles on the road (:func:`road_ids`), the decisions, :func:`step_vehicles`
(:func:`step_body`: :func:`step_front`, the discretionary lane changes, :func:`step_back`)
and :func:`record_due_row`. It advances many
steps in one compiled call, live merge plans included (executed from the plan table of the
compiled state), and hands a step to Python only for its decisions (:func:`needs_python`): a
ramp vehicle entering the control zone (key vehicles, a first plan), a live plan due for a
replan (:func:`hcomc.sim.step.plans.due_plans`), or every step of a run whose CAVs confirm
their lane changes by the game (Section III-B, in Python). The engine then finishes that
step with the same kernels (:meth:`hcomc.sim.engine.Simulation.resume`).

Each equation is called from its one home (:mod:`hcomc.equations`, :mod:`hcomc.safety`,
:mod:`hcomc.sim.perception`, :mod:`hcomc.sim.mobil`, :mod:`hcomc.sim.neighbours`). Semantics
(order of operations, who sees whom, events) are those documented in
:mod:`hcomc.sim.engine`.
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel
from hcomc.control.key_vehicles import key_vehicle_indices
from hcomc.sim.arrays import nonzero_into
from hcomc.sim.lane_table import L_LEFT, L_ZONE
from hcomc.sim.log.slots import claim_slots
from hcomc.sim.neighbours import LaneIndex
from hcomc.sim.perception import advance_errors_of
from hcomc.sim.step.collisions import check_collisions
from hcomc.sim.step.lane_change import (
    commanded_changes,
    discretionary_changes,
    start_lane_changes,
)
from hcomc.sim.step.motion import (
    StepAccelerations,
    bookkeeping,
    follow_many,
    integrate,
    lateral,
    step_accelerations,
)
from hcomc.sim.step.plans import (
    due_plans,
    execute_plans,
    finish_plans,
    following_into,
    holding_mask,
    virtual_rows_into,
)
from hcomc.sim.step.release import release
from hcomc.sim.step.state import (
    CAV_GAME,
    CONTROLLER,
    DECAY,
    DECIDE_EVERY,
    DONE,
    DT,
    ERRORS,
    FLUSH,
    GROW_LOG,
    INNOV_CURSOR,
    KEYS,
    KEYS_COMPILED,
    KICK,
    LOG_EVERY,
    N_EVENTS,
    N_KEYS,
    N_PLANS,
    N_WARMUP,
    NEED_PYTHON,
    PLATOON,
    ROWS,
    S_FOLLOWING,
    S_HOLDING,
    S_IDS,
    S_VV,
    S_VV_FOL,
    STEP,
    STOP_AT_KEYS,
    VEHICLE_STEPS,
    WARMUP,
    CoreArrays,
    push_history,
)

__all__ = [
    "begin_step", "commanded_changes", "count_on_road", "discretionary_changes",
    "draw_innovations", "due_plans", "end_step", "follow_many", "holding", "on_road",
    "push_history", "record_due_row", "record_row", "release", "road_ids", "run_steps",
    "start_lane_changes", "step_accelerations", "step_alone", "step_back", "step_body",
    "step_finish", "step_front", "step_time", "step_vehicles",
]  # fmt: skip


@kernel
def step_finish(
    c: CoreArrays, ids: np.ndarray, t: float, acc: np.ndarray, index: LaneIndex
) -> None:
    """Collisions, integration, lateral motion, exits, the HDVs' error processes (the step's
    row of pre-drawn innovations, :func:`draw_innovations`) and the end of the step."""
    check_collisions(c, t, index)
    integrate(c, ids, acc)
    lateral(c, ids, t)
    bookkeeping(c, ids, t)
    if c.flags[ERRORS] > 0:
        xi = c.innov[c.counters[INNOV_CURSOR]]
        advance_errors_of(c.w_gap, c.w_ttc, ids, c.is_hdv, xi, c.consts[DECAY], c.consts[KICK])
    end_step(c)


@kernel
def end_step(c: CoreArrays) -> None:
    """The end of every step, with vehicles on the road or none: the next row of innovations
    (so that row k of a block always belongs to its k-th step) and the step counted, its
    state pushed into the perception history."""
    if c.flags[ERRORS] > 0:
        c.counters[INNOV_CURSOR] += 1
    push_history(c)


# --------------------------------------------------------------------------- record
@kernel
def record_row(c: CoreArrays, k: int, t: float) -> bool:
    """Write log row k for the vehicles on the road, each in its slot column
    (:func:`hcomc.sim.log.slots.claim_slots`); the other cells keep the log's fill (NaN,
    lane -1, inactive), so a row costs what is on the road. False, writing nothing, when the
    log needs more columns first. Once the slots are claimed, their holders are the vehicles
    on the road, so the row visits the slots, not every vehicle of the run."""
    if not claim_slots(c.active, c.log_slot, c.log_span, c.log_owner, k):
        return False
    c.log_t[k] = t
    active, owner, x, y, v, a = c.active, c.log_owner, c.x, c.y, c.v, c.a
    heading, lane = c.heading, c.lane
    log_x, log_y, log_v, log_a = c.log_x, c.log_y, c.log_v, c.log_a
    log_heading, log_lane, log_active = c.log_heading, c.log_lane, c.log_active
    for s in range(owner.size):
        i = owner[s]
        if i >= 0 and active[i]:
            log_active[k, s] = True
            log_x[k, s], log_y[k, s], log_v[k, s] = x[i], y[i], v[i]
            log_a[k, s], log_heading[k, s], log_lane[k, s] = a[i], heading[i], lane[i]
    return True


# ---------------------------------------------------------------------- one step
@kernel
def step_front(c: CoreArrays, ids: np.ndarray, t: float) -> StepAccelerations:
    """The accelerations of a step (:func:`step_accelerations`) with the live plans' followers
    and virtual leaders, then the lane changes the plans command now. Returns
    ``(acc, changing, index, lead)``, views of the step's work rows (valid
    until the next step)."""
    n_plans = c.counters[N_PLANS]
    following = following_into(c.plan_int, n_plans, c.scratch_b[S_FOLLOWING, : c.x.size])
    fol, rows = c.scratch_int[S_VV_FOL], c.scratch_f[S_VV : S_VV + 4]
    m = virtual_rows_into(c.plan_int, c.plan_f, n_plans, t, c.x, c.v, c.a, c.length, fol, rows)
    acc, changing, index, lead = step_accelerations(
        c, ids, t, following, fol[:m], rows[0, :m], rows[1, :m], rows[2, :m], rows[3, :m]
    )
    if n_plans > 0:
        execute_plans(c, ids, t, lead, index)
    return acc, changing, index, lead


@kernel
def holding(c: CoreArrays) -> np.ndarray:
    """Vehicles that make no discretionary change now: held for a live plan
    (:func:`hcomc.sim.step.plans.holding_mask`) or driven from outside. A vehicle that is
    not an HDV is a CAV (:class:`hcomc.road.Kind` has these two). A view of the step's
    work row."""
    out = c.scratch_b[S_HOLDING, : c.x.size]
    out[:] = c.held
    n_plans = c.counters[N_PLANS]
    if n_plans > 0:
        out |= holding_mask(c.plan_int, n_plans, ~c.is_hdv)
    return out


@kernel
def step_back(c: CoreArrays, ids: np.ndarray, t: float, acc: np.ndarray, index: LaneIndex) -> None:
    """The end of a step (:func:`step_finish`), then the plans that ended are dropped."""
    step_finish(c, ids, t, acc, index)
    if c.counters[N_PLANS] > 0:
        finish_plans(c)


@kernel
def step_body(c: CoreArrays, ids: np.ndarray, t: float) -> None:
    """One step of the vehicles ``ids`` after release and decisions, without the game."""
    acc, changing, index, lead = step_front(c, ids, t)
    if (c.counters[STEP] % c.flags[DECIDE_EVERY] == 0) and c.flags[PLATOON] == 0:
        chosen, target = discretionary_changes(c, ids, changing, holding(c), lead, index)
        start_lane_changes(c, chosen, target, t, c.consts[:0])  # empty: their own durations
    step_back(c, ids, t, acc, index)


# ----------------------------------------------------------------------------- loop
@kernel
def needs_python(c: CoreArrays, t: float, ids: np.ndarray) -> bool:
    """Whether the step at t needs the engine's Python side: a controller decision (a ramp
    vehicle entering its lane's control zone: key vehicles and a first plan; a live plan
    due for a replan) or game-confirmed lane changes. In a run whose key groups are found
    compiled (flag ``KEYS_COMPILED``: no controller, no listeners) a ramp vehicle entering
    the zone needs none: its key group is recorded here (:func:`record_key_group`). ``ids``
    are the vehicles on the road (:func:`road_ids`), the only ones that can enter a zone."""
    if c.flags[CAV_GAME] > 0:
        return True
    zone, controlled = c.road_f[L_ZONE], c.flags[CONTROLLER] > 0
    compiled = c.flags[KEYS_COMPILED] > 0
    x, lane, origin, target = c.x, c.lane, c.origin, c.target
    for i in ids:
        if (
            x[i] >= zone[lane[i]]  # first: false at once on a lane without a zone (inf)
            and origin[i] == target[i]
            and (not c.identified[i] or (controlled and not c.planned[i]))
        ):
            if compiled and not c.identified[i] and c.counters[N_KEYS] < c.key_table.shape[0]:
                record_key_group(c, i)
                continue
            return True  # fmt: skip
    return c.counters[N_PLANS] > 0 and due_plans(c, t).size > 0


@kernel
def record_key_group(c: CoreArrays, vr: int) -> None:
    """The key vehicles of ramp vehicle ``vr`` at its control-zone entry (Section II-A:
    :func:`hcomc.control.key_vehicles.key_vehicle_indices` with the lane left of its ramp
    lane and the one beyond, the lanes of its ramp as :func:`hcomc.sim.roads.ramp_of` gives
    them), written with the step into the next row of ``key_table``: what the engine's
    Python side records at a decision step
    (:meth:`hcomc.sim.engine.Simulation._identify_key_vehicles`), taken from there by
    :meth:`hcomc.sim.engine_setup.EngineSetup.take_key_groups`."""
    left = c.road_int[L_LEFT]
    lane_1 = left[c.lane[vr]]
    lane_2 = left[lane_1] if lane_1 >= 0 else -1
    row = c.key_table[c.counters[N_KEYS]]
    row[0] = c.counters[STEP]
    row[1:] = key_vehicle_indices(c.x, c.lane, c.active, vr, lane_1, lane_2)
    c.counters[N_KEYS] += 1
    c.identified[vr] = True


@kernel
def step_time(c: CoreArrays) -> float:
    """The time t [s] of the step the state is at (negative during the warm-up)."""
    return -c.consts[WARMUP] + c.counters[STEP] * c.consts[DT]


_DUE = 1e-9
"""Tolerance of "due at t" (``d_t <= t + 1e-9``), the same as :func:`release`'s."""


@kernel
def draw_innovations(c: CoreArrays, rng: np.random.Generator) -> None:
    """The HDVs' error innovations of the next ``len(innov)`` steps from the current one,
    drawn from the run's generator step by step: step k's row gets
    ``rng.standard_normal((2, m_k))`` in its first ``m_k`` columns, ``m_k`` the vehicles due
    by step k's time (the demand is sorted by release time, so these are vehicles
    ``0 .. m_k - 1``, and no other vehicle can be on the road at step k); the other columns
    are not read.

    The generator's consumption up to step k therefore depends only on the release times due
    by then, not on the number of vehicles of the run (a shorter run of a seed draws exactly
    what a longer one draws up to its end) nor on who is on the road (the undisturbed run,
    without the ramp vehicles, draws the same)."""
    first, warmup, dt = c.counters[STEP], c.consts[WARMUP], c.consts[DT]
    for k in range(c.innov.shape[0]):
        t = -warmup + (first + k) * dt  # step_time of step first + k
        m = np.searchsorted(c.d_t, t + _DUE, side="right")
        row = c.innov[k]
        for j in range(2):
            for i in range(m):
                row[j, i] = rng.standard_normal()


@kernel
def begin_step(c: CoreArrays, rng: np.random.Generator) -> bool:
    """The start of every step, before any decision: room in the event buffer for the step's
    events (False, doing nothing, when the buffer must be emptied first), the HDVs' error
    innovations of the next steps when the drawn ones are used up
    (:func:`draw_innovations`, from the run's generator, the same stream whoever calls), then
    the release of the vehicles due at t. Doing it twice in one step changes nothing."""
    if c.counters[N_EVENTS] + 8 * c.x.size + 64 > c.ev_t.size:
        return False
    if c.flags[ERRORS] > 0 and c.counters[INNOV_CURSOR] >= c.innov.shape[0]:
        draw_innovations(c, rng)
        c.counters[INNOV_CURSOR] = 0
    release(c, step_time(c))
    return True


@kernel
def road_ids(c: CoreArrays) -> np.ndarray:
    """The vehicles on the road, in index order (a view of the step's work row)."""
    work = c.scratch_int[S_IDS]
    return work[: nonzero_into(c.active, work)]


@kernel
def on_road(c: CoreArrays) -> np.ndarray:
    """The vehicles on the road (:func:`road_ids`), counted into the run's vehicle-steps;
    with none, the step ends here (:func:`end_step`)."""
    ids = road_ids(c)
    count_on_road(c, ids)
    return ids


@kernel(inline="always")
def count_on_road(c: CoreArrays, ids: np.ndarray) -> None:
    """The vehicles ``ids`` on the road counted into the run's vehicle-steps; with none, the
    step ends here (:func:`end_step`)."""
    if ids.size == 0:
        end_step(c)
    c.counters[VEHICLE_STEPS] += ids.size


@kernel
def step_alone(c: CoreArrays, t: float) -> None:
    """One whole step after its start and decisions, without the game (live plans are
    executed from the plan table)."""
    step_vehicles(c, t, road_ids(c))


@kernel
def step_vehicles(c: CoreArrays, t: float, ids: np.ndarray) -> None:
    """:func:`step_alone` of the vehicles on the road ``ids`` (:func:`road_ids`)."""
    count_on_road(c, ids)
    if ids.size > 0:
        step_body(c, ids, t)


@kernel
def record_due_row(c: CoreArrays, log_rows: bool) -> bool:
    """After a step, with ``log_rows``: write the log row due now (every ``log_every``-th
    step after the warm-up). False, writing nothing, when the log must grow first."""
    k = c.counters[STEP] - c.flags[N_WARMUP]
    if log_rows and k > 0 and k % c.flags[LOG_EVERY] == 0:
        if not record_row(c, c.counters[ROWS], step_time(c)):
            return False
        c.counters[ROWS] += 1
    return True


@kernel
def run_steps(c: CoreArrays, stop: int, log_rows: bool, rng: np.random.Generator) -> int:
    """The step driver: advance until step ``stop`` or until Python is needed; returns why it
    stopped. Each step is :func:`begin_step`, the decisions, :func:`step_alone` and
    :func:`record_due_row`; at a decision (:func:`needs_python`) it returns ``NEED_PYTHON``
    after the step's start, and the engine takes the decisions and the rest of that step
    (:meth:`hcomc.sim.engine.Simulation.resume`) with the same kernels. With the flag
    ``STOP_AT_KEYS`` it returns ``KEYS`` after a step in which it recorded a key group.
    """
    while c.counters[STEP] < stop:
        if not begin_step(c, rng):
            return FLUSH
        t = step_time(c)
        keys = c.counters[N_KEYS]
        ids = road_ids(c)  # release is done: who is on the road for the rest of the step
        if needs_python(c, t, ids):
            return NEED_PYTHON
        step_vehicles(c, t, ids)
        if not record_due_row(c, log_rows):
            return GROW_LOG  # the row is written once the log has grown
        if c.flags[STOP_AT_KEYS] > 0 and c.counters[N_KEYS] > keys:
            return KEYS
    return DONE
