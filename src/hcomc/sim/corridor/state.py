"""State of a corridor run in the arrays the compiled step reads and writes.

:class:`Vehicles` holds what does not change during a run (parameters, route), :class:`State`
what does (kinematics, lanes, the sorted lane entries, counters) and what a run measures
(detectors, the space-time grid, collisions, sampled trajectories). Scalars the step reads
are in the float array ``params`` (index constants ``P_*``) and the int array ``counters``
(``C_*``). :mod:`hcomc.sim.corridor.setup` builds both from a corridor.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["State", "Vehicles", "trajectory_buffer"]

OFFSET = 4.0e6
"""Key offset between lane codes [m]; larger than any position on a code."""

# vehicle status
WAITING, ON_ROAD, ARRIVED = 0, 1, 2
# params (floats)
(P_DT, P_LC_DURATION, P_POLITENESS, P_THRESHOLD, P_BIAS, P_SAFE_DECEL, P_MIN_GAP,
 P_EMERGENCY, P_LOOKAHEAD, P_URGENT, P_PERIOD, P_CELL, P_REPLAN, P_WINDOW) = range(14)  # fmt: skip
N_PARAMS = 14
# counters (ints)
(C_STEP, C_ENTRIES, C_VEHICLE_STEPS, C_LANE_CHANGES, C_COLLISIONS, C_ROWS, C_ON_ROAD,
 C_DECIDE_EVERY, C_SAMPLE_EVERY, C_SORTED, C_CONTROLLED, C_PENDING, C_PLANS,
 C_OPEN, C_AGENTS) = range(15)  # fmt: skip
N_COUNTERS = 15
# columns of the measurement arrays
D_COUNT, D_SPEED, D_INVERSE_SPEED, D_OCCUPIED, D_LENGTH = range(5)  # detectors
G_DISTANCE, G_TIME = range(2)  # space-time grid
TRAJECTORY_COLUMNS = {"t": np.float64, "id": np.int32, "x": np.float64, "lane": np.int8,
                      "code": np.int16, "v": np.float64, "a": np.float64}  # fmt: skip
"""Columns of the trajectory samples and their types (38 bytes a sample)."""
COLLISION_COLUMNS = ("t", "follower", "leader", "x", "code")


class Vehicles(NamedTuple):
    """Per-vehicle constants: IDM parameters (``v0 … delta``), body, route."""

    depart: np.ndarray
    v0: np.ndarray  # desired speed, capped by the technical top speed [m/s]
    T: np.ndarray
    s0: np.ndarray
    a: np.ndarray
    b: np.ndarray
    delta: np.ndarray
    length: np.ndarray
    cav: np.ndarray  # bool: connected and automated
    start_code: np.ndarray
    queue_start: np.ndarray
    queue: np.ndarray


class State(NamedTuple):
    """Everything the step changes (module docstring)."""

    x: np.ndarray  # front position [m] along the mainline (ramp roads: continued)
    v: np.ndarray
    a: np.ndarray
    code: np.ndarray  # lane code driven in (-1 off the road)
    target: np.ndarray  # lane code changed into (= code when not changing)
    lc_start: np.ndarray  # start of the current lane change [s]
    lc_dur: np.ndarray  # duration of the current (or last) lane change [s]
    status: np.ndarray  # WAITING, ON_ROAD, ARRIVED
    insert_t: np.ndarray  # [s], nan until inserted
    arrive_t: np.ndarray  # [s], nan until arrived
    exit_code: np.ndarray  # destination off-ramp's code, -1 for the mainline exit
    missed: np.ndarray  # passed its off-ramp (then bound for the mainline exit)
    merge_t: np.ndarray  # when an on-ramp vehicle's change onto the mainline ended [s], nan
    merge_x: np.ndarray  # where it ended [m], nan
    busy: np.ndarray  # step in which the vehicle last took part in an accepted change
    colliding: np.ndarray  # leader the vehicle overlaps, -1 if none
    ids: np.ndarray  # the vehicles on the road at the step's sort (C_ON_ROAD of them)
    v0e: np.ndarray  # the step's desired speed (speed limit applied) [m/s]
    free: np.ndarray  # the step's free-road term of the IDM
    acc: np.ndarray  # the step's acceleration [m/s^2]
    e_veh: np.ndarray  # lane entries (vehicle, code), sorted by code, then x
    e_code: np.ndarray
    e_key: np.ndarray
    code_first: np.ndarray  # the most upstream entry's vehicle per code, -1 if none
    queue_pos: np.ndarray  # per origin: vehicles of its queue inserted so far
    backlog: np.ndarray  # (origins, periods): most vehicles waiting to enter
    params: np.ndarray
    counters: np.ndarray
    detectors: np.ndarray  # (positions, mainline lanes, periods, 5): D_* sums
    det_x: np.ndarray  # detector positions [m]
    grid: np.ndarray  # (x cells, t cells, 2): G_* sums over the mainline lanes
    collisions: np.ndarray  # (capacity, 5): COLLISION_COLUMNS
    traj_t: np.ndarray  # trajectory samples (capacity,), TRAJECTORY_COLUMNS: time [s]
    traj_id: np.ndarray  # vehicle
    traj_x: np.ndarray  # front position [m]
    traj_lane: np.ndarray  # lane: 0 = rightmost mainline lane, -1 - j ramp lane j
    traj_code: np.ndarray  # lane code
    traj_v: np.ndarray  # speed [m/s]
    traj_a: np.ndarray  # acceleration [m/s^2]
    # merge control and merge events (hcomc.sim.corridor.plans)
    zone: np.ndarray  # per code: where an on-ramp's control zone starts [m] (j = 0), nan
    following: np.ndarray  # a VR on its ramp following its live plan (VV0; merge commanded)
    holding: np.ndarray  # makes no discretionary change (commanded or CAV key vehicle)
    plan_int: np.ndarray  # (capacity, N_INT): live plans, columns of hcomc.sim.step.plans
    plan_f: np.ndarray  # (capacity, N_FLOAT)
    pending: np.ndarray  # VRs awaiting the controller (C_PENDING of them)
    view_lane: np.ndarray  # one ramp's local lanes (hcomc.road.Lane), filled on demand
    view_active: np.ndarray  # on one of that ramp's three lanes
    ev_t: np.ndarray  # when VR entered its control zone [s], nan
    ev_group: np.ndarray  # (N, 6): its key vehicles then (MergeGroup order)
    ev_min_ttc: np.ndarray  # over the event's window, VR, VMC, VMR and VNR [s]
    ev_max_drac: np.ndarray  # [m/s^2]
    ev_max_decel: np.ndarray  # hardest braking of those vehicles [m/s^2]
    ev_vmc_v: np.ndarray  # VMC's speed at identification [m/s]
    ev_vmc_min_v: np.ndarray  # VMC's lowest speed in the window [m/s]
    ev_released: np.ndarray  # VR's plan gave up its commanded merge (gap acceptance)
    ev_open: np.ndarray  # VRs whose window is open (C_OPEN of them)
    # agents' vehicles (learning environments; C_AGENTS of them, 0: the arrays are not read)
    agent_acc: np.ndarray  # acceleration it is driven at [m/s^2]; nan: its own model
    agent_lane: np.ndarray  # lane code it is to change into at the next step, -1: none


def trajectory_buffer(capacity: int) -> dict[str, np.ndarray]:
    """Empty trajectory columns for ``capacity`` samples, by :class:`State` field."""
    return {f"traj_{name}": np.zeros(capacity, dtype=dtype)
            for name, dtype in TRAJECTORY_COLUMNS.items()}  # fmt: skip
