"""Building one run's log and the arrays of the compiled step
(:class:`~hcomc.sim.step.state.CoreArrays`) from its config, demand, fleet and HDV
perception."""

from __future__ import annotations

import numpy as np

from hcomc.config import ConfigError, ScenarioConfig
from hcomc.equations.transition import transition_gamma
from hcomc.interface import Fleet
from hcomc.sim.demand import Demand
from hcomc.sim.lane_change_decisions import lane_change_params
from hcomc.sim.lane_table import KIND_ON, L_CENTRE, L_KIND, L_SPEED, LaneTable
from hcomc.sim.log import SimulationLog
from hcomc.sim.manifest import build_manifest
from hcomc.sim.mobil import NOT_KNOWN
from hcomc.sim.perception_state import Perception
from hcomc.sim.step import state as layout
from hcomc.sim.step.plans import N_FLOAT, N_INT
from hcomc.sim.step.state import Core, CoreArrays

INNOVATION_STEPS = 64
"""Steps of HDV estimation-error innovations drawn at a time (refilled from the run's generator
by the compiled loop or by the engine's Python step)."""


FIRST_SLOTS = 64
"""Slot columns a run's log starts with beyond one for each vehicle due by its first row
(:mod:`hcomc.sim.log.slots`): a scene that starts full need not widen its log at once, a
copy of every column; :func:`widen_log` adds more when more vehicles are on the road at
once, up to one per vehicle."""


def initial_slots(demand: Demand) -> int:
    """The slot columns a run's log starts with: one for each vehicle due by its first row
    (at most that many are on the road then) and :data:`FIRST_SLOTS` more, at most one per
    vehicle."""
    return min(demand.n, int(np.count_nonzero(demand.t <= 0.0)) + FIRST_SLOTS)


def allocate_log(
    config: ScenarioConfig, seed: int, demand: Demand, fleet: Fleet, rows: int
) -> SimulationLog:
    """The empty log of a run (``rows`` logging rows, slot columns for its vehicles) with
    the run's manifest; a clear error when it would exceed ``log_memory_limit``."""
    slots = initial_slots(demand)
    check_log_memory(config, rows, demand.n, slots)
    meta = build_manifest(seed=seed, config=config,
                          extra={"dt": config.dt, "log_interval": config.log_interval})  # fmt: skip
    return SimulationLog.allocate(
        rows, demand.n, dt=config.log_interval, kind=demand.kind, length=fleet.length,
        width=fleet.width, meta=meta, slots=slots,
    )  # fmt: skip


def check_log_memory(config: ScenarioConfig, rows: int, vehicles: int, slots: int) -> None:
    """Raise a clear ``ConfigError`` when a log of ``rows`` rows and ``slots`` columns (that
    many vehicles on the road at once) would exceed ``log_memory_limit``."""
    need = SimulationLog.bytes_needed(rows, vehicles, slots) / 2**30
    if need > config.log_memory_limit:
        raise ConfigError(
            f"key 'log_memory_limit' = {config.log_memory_limit} GiB: this run's log needs "
            f"{need:.2f} GiB ({rows} rows x {slots} vehicles on the road at once); allowed: "
            "a larger log_memory_limit, a coarser log_interval or a shorter duration"
        )


def widen_log(config: ScenarioConfig, log: SimulationLog, on_road: int = 0) -> None:
    """Widen ``log``'s slot columns when more vehicles are on the road at once than it has
    columns: to twice as many, or at once to ``on_road`` (one column each) when that is more
    (a scene that starts full widens once, not a doubling at a time), within
    ``log_memory_limit``."""
    slots = min(max(2 * log.n_slots, on_road), log.n_vehicles)
    if slots <= log.n_slots:
        raise RuntimeError("the log has a column per vehicle and still no free one")
    check_log_memory(config, log.n_steps, log.n_vehicles, slots)
    log.grow_slots(slots)


def adopt_log_columns(arrays: CoreArrays, core: Core, log: SimulationLog) -> CoreArrays:
    """Point a run's compiled state ``core`` at ``log``'s current slot columns (after they
    grew); returns ``arrays`` with the same fields replaced."""
    arrays = arrays._replace(**log_columns(log))
    core.adopt(arrays)
    return arrays


def build_arrays(
    config: ScenarioConfig,
    lanes: LaneTable,
    demand: Demand,
    release_last: np.ndarray,
    fleet: Fleet,
    per: Perception,
    log: SimulationLog,
    *,
    counterfactual: bool,
    controlled: bool,
    n_warmup: int,
    decide_every: int,
    log_every: int,
) -> CoreArrays:
    """The state of a run on the road ``lanes`` before its first step (no vehicle released
    yet), writing into ``log``; ``release_last`` is the last lane code each lane's release
    queue may release into (:attr:`hcomc.sim.scene.Scene.release_last`).

    ``counterfactual`` leaves the ramp queues empty (the undisturbed run); ``controlled``
    says whether a merge controller plans for ramp vehicles entering the control zone.
    """
    n = demand.n
    hdv = config.hdv
    on_ramp = lanes.ints[L_KIND] == KIND_ON
    queues = [
        np.flatnonzero(demand.lane == code)
        if not (counterfactual and on_ramp[code])
        else np.empty(0, dtype=np.int64)
        for code in range(lanes.n_lanes)
    ]
    perceive = per.errors or max(per.taus) > 0
    f8, i8, b1 = np.float64, np.int64, np.bool_
    consts = np.zeros(layout.N_CONSTS)
    consts[[layout.DT, layout.WARMUP]] = config.dt, config.warmup
    consts[layout.EMERGENCY] = config.lane_change.emergency_decel
    consts[[layout.LOOKAHEAD, layout.URGENT]] = (
        config.lane_change.exit_lookahead, config.lane_change.urgent_distance
    )  # fmt: skip
    consts[layout.GAMMA] = transition_gamma(config.lane_change.transition_tolerance)
    consts[[layout.DECAY, layout.KICK]] = per.decay, per.kick
    consts[[layout.GAP_ERROR, layout.TTC_ERROR]] = hdv.gap_error, hdv.inverse_ttc_error
    consts[layout.REPLAN_PERIOD] = config.control.replan_period
    flags = np.zeros(layout.N_FLAGS, dtype=i8)
    flags[layout.PERCEIVE], flags[layout.ERRORS] = perceive, per.errors
    flags[layout.PLATOON] = config.scenario == "platoon"
    flags[layout.DECIDE_EVERY], flags[layout.LOG_EVERY] = decide_every, log_every
    flags[layout.N_WARMUP] = n_warmup
    flags[layout.CONTROLLER] = controlled
    flags[layout.CAV_GAME] = config.lane_change.cav_game
    limits = np.concatenate([lanes.sec_speed, lanes.floats[L_SPEED]])
    flags[layout.SPEED_LIMITS] = bool(np.isfinite(limits).any())
    counters = np.zeros(layout.N_COUNTERS, dtype=i8)
    innov_steps = INNOVATION_STEPS if per.errors else 0
    counters[layout.INNOV_CURSOR] = innov_steps  # empty: drawn when first needed
    n_events = max(4096, 16 * n)
    plan_rows = max(1, int(np.count_nonzero(on_ramp[demand.lane])))  # one plan per VR
    work = max(4 * n + 1, 3 * plan_rows)  # entries, collision pairs, virtual rows
    scratch_int = np.zeros((layout.N_SCRATCH_INT, work), dtype=i8)
    scratch_int[layout.S_KNOWN_LEADER] = NOT_KNOWN  # no acceleration taken yet
    scratch_int[layout.S_VS] = -1  # no lane entries sorted yet (neighbours.PreviousOrder)
    return CoreArrays(
        matrix=np.ascontiguousarray(fleet.matrix), iidm=fleet.iidm.astype(b1),
        length=fleet.length, width=fleet.width, lc_duration=fleet.lc_duration,
        scripted=fleet.scripted.astype(b1), is_hdv=per.is_hdv.astype(b1),
        desired=fleet.matrix[0].copy(), route=demand.route.astype(i8),
        x=np.zeros(n), y=lanes.floats[L_CENTRE, demand.lane], v=np.zeros(n),
        a=np.zeros(n), heading=np.zeros(n), lane=demand.lane.astype(i8),
        origin=demand.lane.astype(i8), target=demand.lane.astype(i8),
        lc_t0=np.zeros(n), lc_x0=np.zeros(n), lc_xf=np.ones(n),
        lc_dur=fleet.lc_duration.copy(),  # a merge plan may set VR's duration
        active=np.zeros(n, dtype=b1), waited=np.zeros(n, dtype=b1),
        identified=np.zeros(n, dtype=b1), planned=np.zeros(n, dtype=b1),
        a_cmd=np.full(n, np.nan), held=np.zeros(n, dtype=b1),
        x_hist=per.x_hist, v_hist=per.v_hist, w_gap=per.w_gap, w_ttc=per.w_ttc,
        taus=per.taus, d_t=demand.t.astype(f8), d_x=demand.x.astype(f8),
        d_v=demand.v.astype(f8), queues=np.concatenate(queues).astype(i8),
        queue_start=np.cumsum([0, *(q.size for q in queues)]).astype(i8),
        queue_pos=np.zeros(lanes.n_lanes, dtype=i8), queue_last=release_last.astype(i8),
        colliding=np.zeros(8 * n + 8, dtype=i8),
        ev_t=np.zeros(n_events), ev_kind=np.zeros(n_events, dtype=i8),
        ev_vehicle=np.zeros(n_events, dtype=i8), ev_other=np.zeros(n_events, dtype=i8),
        ev_x=np.zeros(n_events), ev_value=np.zeros(n_events), counters=counters,
        consts=consts, flags=flags, plan_int=np.zeros((plan_rows, N_INT), dtype=i8),
        plan_f=np.zeros((plan_rows, N_FLOAT)), key_table=np.zeros((plan_rows, 7), dtype=i8),
        road_int=lanes.ints, road_f=lanes.floats,
        sec_x0=lanes.sec_x0, sec_speed=lanes.sec_speed, main_end=lanes.main_end,
        lc_params=lane_change_params(config.lane_change),
        profile=np.asarray(config.platoon.profile, dtype=f8).reshape(-1, 2),
        innov=np.zeros((innov_steps, 2, n)), log_t=log.t, **log_columns(log),
        log_slot=log.slot, log_span=log.span,
        scratch_int=scratch_int,
        scratch_f=np.zeros((layout.N_SCRATCH_F, work)),
        scratch_b=np.zeros((layout.N_SCRATCH_B, 2 * n), dtype=b1),
    )  # fmt: skip


def log_columns(log: SimulationLog) -> dict[str, np.ndarray]:
    """The :class:`CoreArrays` fields of ``log``'s slot columns (the same buffers)."""
    cells = log.cells
    return {
        "log_x": cells["x"], "log_y": cells["y"], "log_v": cells["v"], "log_a": cells["a"],
        "log_heading": cells["heading"], "log_lane": cells["lane"],
        "log_active": cells["active"], "log_owner": log.owner,
    }  # fmt: skip
