"""Stalled vehicles: broken-down cars standing on an acceleration lane for a whole run (a
config's ``[[faults]]`` entries of kind ``stalled_vehicle``,
:class:`hcomc.config.impairment_tables.FaultParams`).

A stalled vehicle is a vehicle of the run like any other, so that the engine's car
following, perception, lane changes, collision checks and log see it without a rule of
their own. It is appended to the scene's demand and fleet (the last columns of the log: the
other vehicles keep their indices, draws and release times, so a run with a stalled vehicle
is paired with the nominal run of its seed), stands on the road from the first step (it is
in no release queue; its release time is infinite), driven from outside at zero
acceleration (:func:`hcomc.sim.step.state.command`: no lane change of its own), and is
recorded as identified and planned, so that no controller is ever asked to plan for it.

Where the acceleration lane ends, the engine reads from its lane table. In the run's own
copy of it (:func:`blocked_lanes`) the lane ends where a vehicle can still steer around the
stalled vehicle: the vehicles behind it (every ramp vehicle: it stands there before the
first one enters) merge before it, brake for it and, stopped before it, wait for a gap, and
their merge plans fail there, as at the lane's end. The controllers are given the road as built
(:attr:`hcomc.sim.engine_setup.EngineSetup.ramps`): they are not told of the obstacle and
see it only as a standing vehicle in the traffic.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from hcomc._typing import IntArray
from hcomc.config import ConfigError, ScenarioConfig
from hcomc.config.impairment_tables import FaultParams
from hcomc.interface import Fleet
from hcomc.road import Kind
from hcomc.sim.demand import Demand
from hcomc.sim.lane_table import (
    ENDS_BLOCKED,
    KIND_MAIN,
    KIND_ON,
    L_END,
    L_ENDS,
    L_KIND,
    L_LEFT,
    L_OPENS,
    MIN_CHANGE_LENGTHS,
    LaneTable,
)
from hcomc.sim.scene import Scene
from hcomc.sim.step.state import CoreArrays

__all__ = ["acceleration_lanes", "blocked_lanes", "least_position", "place_stalled",
           "room_to_steer", "stalled_faults", "with_stalled"]  # fmt: skip


def stalled_faults(faults: Sequence[FaultParams]) -> list[tuple[int, FaultParams]]:
    """The ``stalled_vehicle`` entries of a ``[[faults]]`` list, with their indices."""
    return [(k, f) for k, f in enumerate(faults) if f.kind == "stalled_vehicle"]


def acceleration_lanes(lanes: LaneTable) -> IntArray:
    """The codes of the road's acceleration lanes (the on-ramp lanes next to the mainline),
    one per on-ramp, in the order of the ramps along the road."""
    ints = lanes.ints
    on = lanes.codes_of_kind(KIND_ON)
    return np.array([c for c in on.tolist() if ints[L_KIND, ints[L_LEFT, c]] == KIND_MAIN],
                    dtype=np.int64)  # fmt: skip


def _placement(lanes: LaneTable, k: int, f: FaultParams, least: float) -> tuple[int, float]:
    """(lane code, front position [m]) of stalled vehicle entry ``k``, checked against the
    road: a clear error naming the key when the ramp does not exist or the position is not
    on its acceleration lane at least ``least`` past its start (:func:`least_position`)."""
    codes = acceleration_lanes(lanes)
    if f.ramp >= codes.size:
        raise ConfigError(
            f"key 'faults[{k}].ramp' = {f.ramp}: the road has {codes.size} on-ramp(s); "
            f"allowed: 0 to {codes.size - 1}"
        )
    code = int(codes[f.ramp])
    start, end = float(lanes.floats[L_OPENS, code]), float(lanes.floats[L_END, code])
    if not least <= f.position <= end - start:
        raise ConfigError(
            f"key 'faults[{k}].position' = {f.position}: allowed: {least:g} to "
            f"{end - start:g} m past the acceleration lane's start (nearer its start a ramp "
            "vehicle stopped before the stalled car could not steer around it; the lane "
            "ends at the upper bound)"
        )
    return code, start + f.position


def room_to_steer(fleet: Fleet, min_gap: float) -> float:
    """[m] How far before a stalled vehicle's rear a vehicle must stop to steer around it:
    ``3 L + min_gap``, L the longest vehicle (:data:`~hcomc.sim.lane_table.MIN_CHANGE_LENGTHS`
    of road for a lane change from a standstill, MOBIL's ``min_gap`` to the vehicle ahead)."""
    return MIN_CHANGE_LENGTHS * float(fleet.length.max()) + min_gap


def least_position(fleet: Fleet, config: ScenarioConfig) -> float:
    """[m] The least ``position`` of a stalled vehicle past its acceleration lane's start
    that lets the ramp vehicles merge before it: its length, the room to steer around it
    (:func:`room_to_steer`) and the jam distance s0 at which a vehicle stops before the lane's
    end, so that it stops where it may leave the lane."""
    return (config.road.vehicle_length + room_to_steer(fleet, config.lane_change.min_gap)
            + float(fleet.s0.max()))  # fmt: skip


def with_stalled(scene: Scene, config: ScenarioConfig) -> tuple[Scene, IntArray]:
    """``scene`` with ``config``'s stalled vehicles appended to its demand and fleet (an
    HDV each, parameters of the scenario's HDVs, released never: :func:`place_stalled` puts
    them on the road), and their indices; ``scene`` itself when there are none."""
    entries = stalled_faults(config.faults)
    if not entries:
        return scene, np.empty(0, dtype=np.int64)
    extra = Fleet.build(config, np.full(len(entries), Kind.HDV), np.zeros(len(entries), bool))
    fleet = Fleet(**{f.name: np.concatenate([getattr(scene.fleet, f.name),
                                             getattr(extra, f.name)], axis=-1)
                     for f in dataclasses.fields(Fleet)})  # fmt: skip
    least = least_position(fleet, config)
    placed = [_placement(scene.lanes, k, f, least) for k, f in entries]
    m, d = len(placed), scene.demand
    ids = np.arange(d.n, d.n + m, dtype=np.int64)
    lane = np.array([code for code, _ in placed], dtype=d.lane.dtype)
    demand = Demand(
        t=np.append(d.t, np.full(m, math.inf)), x=np.append(d.x, [x for _, x in placed]),
        v=np.append(d.v, np.zeros(m)), lane=np.append(d.lane, lane),
        kind=np.append(d.kind, np.full(m, Kind.HDV, dtype=d.kind.dtype)),
        scripted=np.append(d.scripted, np.zeros(m, dtype=bool)),
        route=np.append(d.route, np.full(m, -1, dtype=d.route.dtype)),
    )  # fmt: skip
    vclass = np.append(scene.vclass, np.zeros(m, dtype=np.int64)) if scene.classes else (
        scene.vclass)  # fmt: skip
    return dataclasses.replace(scene, demand=demand, fleet=fleet, vclass=vclass), ids


def blocked_lanes(
    lanes: LaneTable, demand: Demand, fleet: Fleet, ids: IntArray, min_gap: float
) -> LaneTable:
    """The engine's copy of ``lanes`` in which each acceleration lane with stalled vehicles
    ``ids`` ends where a vehicle stopped before the first of them can still steer around it:
    ``3 L + min_gap`` before its rear (``L`` the run's longest vehicle, ``min_gap`` MOBIL's,
    :attr:`~hcomc.config.LaneChangeParams.min_gap`). A lane change takes at least ``3 L`` of
    road (Eq. 4-6 as the engine starts them), so MOBIL starts none towards a standing vehicle
    nearer than that (:mod:`hcomc.sim.mobil`): a vehicle that stopped at its rear would
    wait for good. The lane is marked :data:`~hcomc.sim.lane_table.ENDS_BLOCKED`: its end
    stops every vehicle in it, one following a merge plan too, and a changer whose change
    would not be over ``3 L`` past it (Eq. 4-6 move a changer sideways only as it moves
    along: one whose change ends later would still be in the lane at the stalled vehicle).
    ``lanes`` itself without stalled vehicles."""
    if ids.size == 0:
        return lanes
    ints, floats = lanes.ints.copy(), lanes.floats.copy()
    room = room_to_steer(fleet, min_gap)
    for i in ids.tolist():
        code = int(demand.lane[i])
        floats[L_END, code] = min(floats[L_END, code], demand.x[i] - fleet.length[i] - room)
        ints[L_ENDS, code] = ENDS_BLOCKED
    return lanes._replace(ints=ints, floats=floats)


def place_stalled(c: CoreArrays, ids: IntArray, *, counterfactual: bool) -> None:
    """Put the stalled vehicles ``ids`` on the road of a run's state before its first step:
    standing at their positions, driven from outside at zero acceleration, recorded as
    identified, planned and waiting (no controller plans for them; no wait is logged). The
    undisturbed run (``counterfactual``), which releases no ramp vehicle, has none."""
    if counterfactual or ids.size == 0:
        return
    c.x[ids], c.v[ids], c.a[ids] = c.d_x[ids], 0.0, 0.0
    c.x_hist[:, ids], c.v_hist[:, ids] = c.d_x[ids], 0.0
    c.active[ids] = c.identified[ids] = c.planned[ids] = c.waited[ids] = True
    c.a_cmd[ids], c.held[ids] = 0.0, True
