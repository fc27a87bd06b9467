"""State of the compiled simulation step: the :class:`CoreArrays` and their layout.

:class:`CoreArrays` holds every array the step reads or writes (per-vehicle parameters and
state, the HDV perception buffers, the demand queues, the event buffer, counters, the plan
table of the live merge plans, the log). The kernels of :mod:`hcomc.sim.step.loop` receive them
as one :class:`Core`, a compiled reference record over the same buffers: passing it costs one
pointer, whatever the number of arrays (a tuple of arrays would be unpacked and
reference-counted array by array at every call). Its fields are borrowed views
(:func:`hcomc._jit.borrow_all`), so reading one in a kernel counts no reference either.
Python reads and writes the state through the :class:`CoreArrays`.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numba.core import types
from numba.experimental import structref

from hcomc._jit import borrow_all, kernel

# event kinds (the IntEnum of hcomc.sim.log, as plain ints)
EV_INSERTION, EV_LC_START, EV_LC_END, EV_MERGE, EV_COLLISION, EV_WAIT, EV_EXIT = range(7)
EV_FALLBACK, EV_MISSED_EXIT, EV_LC_ABORT = 8, 9, 10
# counters
STEP, VEHICLE_STEPS, N_EVENTS, N_COLLIDING, INNOV_CURSOR, ROWS, COLLISIONS, N_PLANS = range(8)
N_KEYS = 8  # key groups found by the compiled loop (rows of ``key_table``)
N_COUNTERS = 9
# consts
(DT, WARMUP, EMERGENCY, GAMMA, DECAY, KICK, GAP_ERROR, TTC_ERROR, REPLAN_PERIOD,
 LOOKAHEAD, URGENT) = range(11)  # fmt: skip
N_CONSTS = 11
# flags
(PERCEIVE, ERRORS, PLATOON, DECIDE_EVERY, LOG_EVERY, N_WARMUP, CONTROLLER,
 CAV_GAME, SPEED_LIMITS) = range(9)  # fmt: skip
# the compiled loop finds key groups itself (a run without a controller or listeners), and
# returns after a step in which it found one (a caller waiting for key vehicles)
KEYS_COMPILED, STOP_AT_KEYS = 9, 10
N_FLAGS = 11
# reasons run_steps returns
DONE, NEED_PYTHON, FLUSH, GROW_LOG, KEYS = range(5)
# rows of the step's work arrays (scratch_int, scratch_f: width >= 4N + 1; scratch_b: 2N).
# A step writes its per-vehicle and per-entry arrays into these rows instead of allocating
# them; the arrays a kernel returns from them are valid until the same row is next written
# (the next step). S_VS and S_LS, the sorted entries' vehicles and lanes, are also where the
# next step's sort starts from (hcomc.sim.neighbours.PreviousOrder): only that sort writes them
(S_IDS, S_LEAD, S_VEH, S_LANE, S_ORDER, S_BUFFER, S_RANK, S_VS, S_LS, S_CODES,
 S_VV_FOL) = range(11)  # fmt: skip
# MOBIL's candidates (hcomc.sim.step.lane_change) and its work rows S_MOBIL .. S_MOBIL + 3
# (hcomc.sim.mobil.mobil_decide_into); the changers of the Eq. 14 blend and their new leaders
S_POS, S_CAND, S_CAND_LANE, S_CAND_LEADER, S_CAND_FOLLOWER, S_CAND_TARGET = range(11, 17)
S_MOBIL = 17
S_CHANGERS, S_CHANGER_IDS, S_NEW_LEADER = range(21, 24)
S_KNOWN_LEADER = 24  # the leader behind which each vehicle's S_KNOWN was taken (MOBIL's reuse)
# where each vehicle's lane entries are in this step's given order (the sort's work rows)
S_FIRST_ENTRY, S_SECOND_ENTRY = 25, 26
N_SCRATCH_INT = 27
S_X, S_KEY, S_KS, S_ACC, S_VV = range(5)  # S_VV .. S_VV + 3: x, v, a, length of virtual rows
S_GAP, S_SPEED, S_LEADER_SPEED, S_LEADER_ACC, S_LEADER_LENGTH = range(9, 14)  # car following
S_MOBIL_F = 14  # .. S_MOBIL_F + 1: MOBIL's work rows over the vehicles
S_NEW_ACC = 16  # the changers' accelerations behind their target-lane leaders
S_MARGIN = 17  # MOBIL's incentive margin of each candidate change
S_URGENCY = 18  # how far each candidate change accepts harder braking (a needed one's)
S_KNOWN = 19  # each vehicle's model acceleration from exact inputs, taken by car following
N_SCRATCH_F = 20
S_CHANGING, S_IN_ORI, S_IN_TGT, S_FOLLOWING, S_HOLDING = range(5)
S_FORCE, S_MOBIL_B = 5, 6  # S_MOBIL_B .. S_MOBIL_B + 1: MOBIL's flags per candidate
N_SCRATCH_B = 8


class CoreArrays(NamedTuple):
    """Every array of one run's step (shape (N,) unless noted)."""

    matrix: np.ndarray  # (7, N): v0, T, s0, a, b, delta, coolness
    iidm: np.ndarray
    length: np.ndarray
    width: np.ndarray
    lc_duration: np.ndarray
    scripted: np.ndarray
    is_hdv: np.ndarray
    desired: np.ndarray  # desired speed v0 before any speed limit [m/s]
    route: np.ndarray  # the off-ramp lane a vehicle leaves by (its code; -1: the mainline's end)
    x: np.ndarray
    y: np.ndarray
    v: np.ndarray
    a: np.ndarray
    heading: np.ndarray
    lane: np.ndarray
    origin: np.ndarray  # lane a change started from (= lane when keeping)
    target: np.ndarray  # lane a change goes to (= lane when keeping)
    lc_t0: np.ndarray
    lc_x0: np.ndarray
    lc_xf: np.ndarray
    lc_dur: np.ndarray
    active: np.ndarray
    waited: np.ndarray
    identified: np.ndarray  # key vehicles recorded at control-zone entry
    planned: np.ndarray  # a controller planned for this ramp vehicle
    a_cmd: np.ndarray  # acceleration commanded from outside (an agent) [m/s^2]; NaN: none
    held: np.ndarray  # makes no discretionary (MOBIL) lane change: driven from outside
    x_hist: np.ndarray  # (K, N) perception ring buffers
    v_hist: np.ndarray
    w_gap: np.ndarray
    w_ttc: np.ndarray
    taus: np.ndarray  # (3,) reaction times on gap, speed, approach rate [s]
    d_t: np.ndarray  # demand: release time, position, speed
    d_x: np.ndarray
    d_v: np.ndarray
    queues: np.ndarray  # vehicles by lane, concatenated
    queue_start: np.ndarray  # (L + 1,) start of each lane's queue in ``queues``
    queue_pos: np.ndarray  # (L,) next vehicle of each queue
    queue_last: np.ndarray  # (L,) the last lane a queue's vehicles may enter by (its own: one)
    colliding: np.ndarray  # pair codes i * N + j of the pairs in contact last step
    ev_t: np.ndarray  # event buffer
    ev_kind: np.ndarray
    ev_vehicle: np.ndarray
    ev_other: np.ndarray
    ev_x: np.ndarray
    ev_value: np.ndarray
    counters: np.ndarray  # int64, see STEP ... N_PLANS
    consts: np.ndarray  # float64, see DT ... REPLAN_PERIOD
    flags: np.ndarray  # int64, see PERCEIVE ... CAV_GAME
    plan_int: np.ndarray  # (P, k) the live merge plans (hcomc.sim.step.plans), first N_PLANS
    plan_f: np.ndarray  # (P, m) their times, positions and cubic coefficients
    key_table: np.ndarray  # (P, 7) key groups found compiled: step, then VR ... VNR (first N_KEYS)
    road_int: np.ndarray  # (4, L) the road's lanes by code (hcomc.sim.lane_table: L_KIND ...)
    road_f: np.ndarray  # (8, L) their centres, widths, begins, ends ... [m] (L_CENTRE ...)
    sec_x0: np.ndarray  # (S,) the road's sections (hcomc.sim.lane_table.LaneTable): starts [m]
    sec_speed: np.ndarray  # (S,) speed limits [m/s]
    main_end: np.ndarray  # (M, S) where mainline lane k ends at or after section s [m]
    lc_params: np.ndarray  # MOBIL parameters (hcomc.sim.lane_change_decisions.lane_change_params)
    profile: np.ndarray  # (k, 2) scripted leader speed profile (t, v)
    innov: np.ndarray  # (m, 2, N) pre-drawn innovations of the estimation errors
    log_t: np.ndarray  # the run's log (SimulationLog's stored arrays, the same buffers)
    log_x: np.ndarray
    log_y: np.ndarray
    log_v: np.ndarray
    log_a: np.ndarray
    log_heading: np.ndarray
    log_lane: np.ndarray
    log_active: np.ndarray
    log_slot: np.ndarray  # the log's slot tables (hcomc.sim.log.slots)
    log_span: np.ndarray
    log_owner: np.ndarray
    scratch_int: np.ndarray  # (N_SCRATCH_INT, >= 4N + 1) the step's work arrays
    scratch_f: np.ndarray  # (N_SCRATCH_F, >= 4N + 1)
    scratch_b: np.ndarray  # (N_SCRATCH_B, 2N) (S_CHANGING ...; up to two candidates each)


@structref.register
class CoreType(types.StructRef):
    """numba type of :class:`Core`."""

    def preprocess_fields(self, fields: Any) -> tuple[tuple[str, Any], ...]:
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class Core(structref.StructRefProxy):
    """The compiled kernels' handle on one run's :class:`CoreArrays` (the same buffers).

    Its fields are views that do not own their memory: an owning array's reference count
    is changed atomically each time a kernel reads it from the record or passes it on, which
    the step's loops would pay hundreds of times a step. The handle keeps the arrays
    it borrows alive itself (:meth:`adopt`)."""

    _arrays: CoreArrays

    def __new__(cls, arrays: CoreArrays) -> Core:
        # numba's own constructor path compiles anew in every process; this
        # one is compiled once and then loaded from numba's cache
        core: Core = _new_core(*arrays)
        core._arrays = arrays
        return core

    def adopt(self, arrays: CoreArrays) -> None:
        """Point the handle at ``arrays``' log columns (after the log grew), which it then
        keeps alive instead of the old ones."""
        set_log_columns(self, arrays.log_x, arrays.log_y, arrays.log_v, arrays.log_a,
                        arrays.log_heading, arrays.log_lane, arrays.log_active,
                        arrays.log_owner)  # fmt: skip
        self._arrays = arrays


structref.define_constructor(Core, CoreType, list(CoreArrays._fields))
structref.define_boxing(CoreType, Core)


@kernel
def _new_core(*arrays: Any) -> Any:
    """A :class:`Core` over borrowed views of ``arrays`` (the fields of :class:`CoreArrays`,
    in order)."""
    return Core(*borrow_all(arrays))


@kernel
def set_log_columns(
    c: Any, x: np.ndarray, y: np.ndarray, v: np.ndarray, a: np.ndarray,
    heading: np.ndarray, lane: np.ndarray, active: np.ndarray, owner: np.ndarray,
) -> None:  # fmt: skip
    """Point the run's state at borrowed views of its log's new (wider) slot columns (use
    :meth:`Core.adopt`, which keeps them alive)."""
    x, y, v, a, heading, lane, active, owner = borrow_all((x, y, v, a, heading, lane, active,
                                                           owner))  # fmt: skip
    c.log_x, c.log_y, c.log_v, c.log_a, c.log_heading = x, y, v, a, heading
    c.log_lane, c.log_active, c.log_owner = lane, active, owner


# ----------------------------------------------------------------------------- events
@kernel(inline="always")
def add_event(
    c: CoreArrays, t: float, kind: int, i: int, other: int, x: float, value: float
) -> None:
    """Append an event to the buffer (the engine flushes it to the log)."""
    k = c.counters[N_EVENTS]
    c.ev_t[k], c.ev_kind[k], c.ev_vehicle[k], c.ev_other[k] = t, kind, i, other
    c.ev_x[k], c.ev_value[k] = x, value
    c.counters[N_EVENTS] = k + 1


@kernel
def command(c: CoreArrays, i: int, accel: float) -> None:
    """Drive vehicle i from outside with acceleration ``accel`` [m/s^2] from the next step on
    (it then makes no lane change of its own); NaN hands it back to its model."""
    c.a_cmd[i] = accel
    c.held[i] = not np.isnan(accel)


@kernel
def push_history(c: CoreArrays) -> None:
    """End of a step: count it and store the state in the perception ring buffer."""
    c.counters[STEP] += 1
    row = c.counters[STEP] % c.x_hist.shape[0]
    c.x_hist[row] = c.x
    c.v_hist[row] = c.v
