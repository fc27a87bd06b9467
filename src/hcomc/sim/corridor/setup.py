"""A corridor run's compiled arrays, built from its configuration: the road's
:class:`~hcomc.sim.corridor.layout.Layout`, the vehicles
(:class:`~hcomc.sim.corridor.fleet.CorridorFleet`), the step's view of them
(:class:`~hcomc.sim.corridor.state.Vehicles`) and a fresh
:class:`~hcomc.sim.corridor.state.State`.

The Python side of those records: they read the corridor (:mod:`hcomc.corridor`, the
configuration), which the kernels that use the records do not import.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc.corridor import Corridor, OnRamp, detector_positions, sections
from hcomc.corridor.layout import main_lane_count, ramp_codes
from hcomc.corridor.schedule import departure_times, draw_classes
from hcomc.rng import make_rng
from hcomc.road import N_ROLES
from hcomc.sim.corridor.fleet import IDM_COLUMNS, CorridorFleet
from hcomc.sim.corridor.layout import KIND_MAIN, KIND_OFF, KIND_ON, Layout
from hcomc.sim.corridor.state import (
    C_CONTROLLED,
    C_DECIDE_EVERY,
    C_SAMPLE_EVERY,
    COLLISION_COLUMNS,
    N_COUNTERS,
    N_PARAMS,
    P_BIAS,
    P_CELL,
    P_DT,
    P_EMERGENCY,
    P_LC_DURATION,
    P_LOOKAHEAD,
    P_MIN_GAP,
    P_PERIOD,
    P_POLITENESS,
    P_REPLAN,
    P_SAFE_DECEL,
    P_THRESHOLD,
    P_URGENT,
    P_WINDOW,
    State,
    Vehicles,
    trajectory_buffer,
)
from hcomc.sim.step.plans import N_FLOAT, N_INT

__all__ = ["allocate", "build_fleet", "build_layout", "ramp_code", "vehicles_of"]


def build_layout(c: Corridor) -> Layout:
    """The :class:`Layout` of corridor ``c``."""
    road, secs = c.road, sections(c.road)
    n_main = main_lane_count(road)
    n_codes = n_main + 2 * len(road.ramps)
    base = ramp_codes(road)
    kinds = {"main": KIND_MAIN, "accel": KIND_ON, "decel": KIND_OFF}
    sec_lanes = np.array([s.lanes for s in secs], dtype=np.int64)
    lane_end = np.full((n_main, len(secs)), np.inf)
    for k in range(n_main):
        end = np.inf
        for s in range(len(secs) - 1, -1, -1):  # from downstream: the next section without k
            if sec_lanes[s] <= k:
                end = secs[s].x0
            lane_end[k, s] = end
    code_kind = np.zeros(n_codes, dtype=np.int64)
    code_x0, code_x1, code_far, code_speed = (np.zeros(n_codes) for _ in range(4))
    code_left = np.full(n_codes, -1, dtype=np.int64)
    code_right = np.full(n_codes, -1, dtype=np.int64)
    for ramp in road.ramps:
        on = isinstance(ramp, OnRamp)
        for j in range(2):
            code = base[ramp.id] + j
            code_kind[code] = KIND_ON if on else KIND_OFF
            code_x0[code], code_x1[code] = ramp.x, ramp.end
            code_far[code] = ramp.x - ramp.ramp_length if on else ramp.end + ramp.ramp_length
            code_speed[code] = road.speed_at(ramp.x)
            code_left[code] = 0 if j == 0 else code - 1
            code_right[code] = code + 1 if j + 1 < ramp.lanes else -1
    return Layout(
        sec_x0=np.array([s.x0 for s in secs]),
        sec_x1=np.array([s.x1 for s in secs]),
        sec_lanes=sec_lanes,
        sec_ramp=np.array([base[s.ramp] if s.ramp else -1 for s in secs], dtype=np.int64),
        sec_kind=np.array([kinds[s.kind] for s in secs], dtype=np.int64),
        sec_speed=np.array([s.speed_limit for s in secs]),
        lane_end=lane_end,
        code_kind=code_kind,
        code_x0=code_x0,
        code_x1=code_x1,
        code_far=code_far,
        code_speed=code_speed,
        code_left=code_left,
        code_right=code_right,
    )


def ramp_code(layout: Layout, ramp_id: str, c: Corridor) -> int:
    """Code of lane j = 0 of ramp ``ramp_id`` of corridor ``c`` in its ``layout``."""
    ids = [r.id for r in c.road.ramps]
    return layout.n_main + 2 * ids.index(ramp_id)


def build_fleet(c: Corridor, layout: Layout, seed: int, duration: float) -> CorridorFleet:
    """Every vehicle of corridor ``c``'s demand that departs before ``duration`` [s],
    classes drawn with ``seed``."""
    d = departure_times(c, duration)
    n = d.time.size
    classes = tuple(c.vehicles)
    vclass, cav = draw_classes(c, d, make_rng(seed))
    idm = np.zeros((n, len(IDM_COLUMNS)))
    for k, name in enumerate(classes):
        for flag in (False, True):
            rows = (vclass == k) & (cav == flag)
            params = c.vehicles[name].idm(flag)
            idm[rows] = [params[col] for col in IDM_COLUMNS]
    length = np.array([c.vehicles[name].length for name in classes])[vclass]
    max_speed = np.array([c.vehicles[name].max_speed for name in classes])[vclass]
    codes = {r.id: ramp_code(layout, r.id, c) for r in c.road.ramps}
    start_code = np.array([codes.get(o, -1) for o in d.origins], dtype=np.int64)[d.origin]
    exit_code = np.array([codes.get(x, -1) for x in d.destinations], dtype=np.int64)
    order = np.argsort(d.origin, kind="stable")
    counts = np.bincount(d.origin, minlength=len(d.origins))
    return CorridorFleet(
        depart=d.time,
        origin=d.origin.astype(np.int64),
        destination=d.destination.astype(np.int64),
        vclass=vclass,
        cav=cav,
        idm=idm,
        length=length,
        max_speed=max_speed,
        start_code=start_code,
        exit_code=exit_code[d.destination],
        queue_start=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
        queue=order.astype(np.int64),
        origins=d.origins,
        destinations=d.destinations,
        classes=classes,
    )


def vehicles_of(fleet: CorridorFleet) -> Vehicles:
    """The compiled step's view of ``fleet``."""
    idm = fleet.idm
    return Vehicles(
        depart=fleet.depart,
        v0=np.minimum(idm[:, 0], fleet.max_speed),
        T=idm[:, 1].copy(),
        s0=idm[:, 2].copy(),
        a=idm[:, 3].copy(),
        b=idm[:, 4].copy(),
        delta=idm[:, 5].copy(),
        length=fleet.length,
        cav=fleet.cav,
        start_code=fleet.start_code,
        queue_start=fleet.queue_start,
        queue=fleet.queue,
    )


def allocate(
    c: Corridor, layout: Layout, fleet: CorridorFleet, duration: float, sample_every: int,
    controlled: bool = False,
) -> State:  # fmt: skip
    """A fresh state for ``fleet`` on ``layout`` over ``duration`` [s]; trajectories sampled
    every ``sample_every`` steps (0: none); ``controlled``: a merge controller decides for
    the vehicles entering the on-ramps' control zones."""
    n = fleet.depart.size
    lc, run, det = c.lane_change, c.corridor, c.detectors
    params = np.zeros(N_PARAMS)
    params[[P_DT, P_LC_DURATION, P_POLITENESS, P_THRESHOLD, P_BIAS, P_SAFE_DECEL, P_MIN_GAP,
            P_EMERGENCY, P_LOOKAHEAD, P_URGENT, P_PERIOD, P_CELL, P_REPLAN, P_WINDOW]] = [
        run.step_length, run.lane_change_duration, lc.politeness, lc.threshold,
        lc.keep_right_bias, lc.safe_decel, lc.min_gap, lc.emergency_decel,
        c.routes.exit_lookahead, c.routes.urgent_distance, det.period, det.cell_length,
        c.control.replan_period, c.merges.window_after,
    ]  # fmt: skip
    counters = np.zeros(N_COUNTERS, dtype=np.int64)
    counters[C_DECIDE_EVERY] = max(1, round(lc.decision_interval / run.step_length))
    counters[C_SAMPLE_EVERY] = sample_every
    counters[C_CONTROLLED] = controlled
    zone = np.full(layout.n_codes, np.nan)
    for ramp in c.road.on_ramps:
        zone[ramp_code(layout, ramp.id, c)] = ramp.x - ramp.control_zone_length
    plans = max(1, int(np.count_nonzero(fleet.start_code >= 0)))
    periods = max(1, math.ceil(duration / det.period - 1e-9))
    positions = np.array(detector_positions(c))
    cells = max(1, math.ceil(layout.length / det.cell_length))
    nan = np.full(n, np.nan)
    return State(
        x=np.zeros(n), v=np.zeros(n), a=np.zeros(n),
        code=np.full(n, -1, dtype=np.int64), target=np.full(n, -1, dtype=np.int64),
        lc_start=nan.copy(), lc_dur=np.full(n, run.lane_change_duration),
        status=np.zeros(n, dtype=np.int64),
        insert_t=nan.copy(), arrive_t=nan.copy(), exit_code=fleet.exit_code.copy(),
        missed=np.zeros(n, dtype=np.bool_), merge_t=nan.copy(), merge_x=nan.copy(),
        busy=np.full(n, -1, dtype=np.int64),
        colliding=np.full(n, -1, dtype=np.int64),
        ids=np.zeros(n, dtype=np.int64), v0e=np.zeros(n), free=np.zeros(n), acc=np.zeros(n),
        e_veh=np.zeros(2 * n + 1, dtype=np.int64), e_code=np.zeros(2 * n + 1, dtype=np.int64),
        e_key=np.zeros(2 * n + 1),
        code_first=np.full(layout.n_codes, -1, dtype=np.int64),
        queue_pos=np.zeros(len(fleet.origins), dtype=np.int64),
        backlog=np.zeros((len(fleet.origins), periods), dtype=np.int64),
        params=params, counters=counters,
        detectors=np.zeros((positions.size, layout.n_main, periods, 5)), det_x=positions,
        grid=np.zeros((cells, periods, 2)),
        collisions=np.zeros((1024, len(COLLISION_COLUMNS))),
        **trajectory_buffer(0),
        zone=zone, following=np.zeros(n, dtype=np.bool_), holding=np.zeros(n, dtype=np.bool_),
        plan_int=np.zeros((plans, N_INT), dtype=np.int64), plan_f=np.zeros((plans, N_FLOAT)),
        pending=np.zeros(n, dtype=np.int64),
        view_lane=np.full(n, -1, dtype=np.int64), view_active=np.zeros(n, dtype=np.bool_),
        ev_t=nan.copy(), ev_group=np.full((n, N_ROLES), -1, dtype=np.int64),
        ev_min_ttc=np.full(n, np.inf), ev_max_drac=np.zeros(n), ev_max_decel=np.zeros(n),
        ev_vmc_v=nan.copy(), ev_vmc_min_v=nan.copy(), ev_released=np.zeros(n, dtype=np.bool_),
        ev_open=np.zeros(n, dtype=np.int64),
        agent_acc=nan.copy(), agent_lane=np.full(n, -1, dtype=np.int64),
    )  # fmt: skip
