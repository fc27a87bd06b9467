"""Lane-change decisions of a fleet from Python: MOBIL and ramp gap acceptance
(:mod:`hcomc.sim.mobil`, whose kernels the compiled step calls) on a snapshot of the
vehicles, with the parameters of the run's :class:`~hcomc.config.LaneChangeParams`.

The SUMO co-simulation decides its vehicles' changes here; the engine reads
:func:`lane_change_params` into its compiled state. Kept apart from the kernels so that they
do not import the configuration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import LaneChangeParams
from hcomc.interface import Fleet
from hcomc.sim.lane_table import LaneTable
from hcomc.sim.mobil import NOT_KNOWN, Candidates, MobilWork, Traffic, mobil_decide_into
from hcomc.sim.neighbours import LaneIndex
from hcomc.sim.step.lane_change import free_target


@dataclass(frozen=True, slots=True)
class Snapshot:
    """Read-only kinematic state of all vehicle slots, shape (N,) each."""

    x: FloatArray
    v: FloatArray
    a: FloatArray


def decide(
    fleet: Fleet,
    snap: Snapshot,
    index: LaneIndex,
    cand: IntArray,
    lane: IntArray,
    leader: IntArray,
    follower: IntArray,
    params: LaneChangeParams,
    lanes: LaneTable,
    target: IntArray | None = None,
    force: BoolArray | None = None,
) -> tuple[IntArray, IntArray]:
    """Accepted lane changes among candidates ``cand``: ``(vehicles, target lanes)``.

    ``lane``, ``leader`` and ``follower`` are the candidates' current lane and neighbours,
    ``lanes`` the road's lane table. ``target`` defaults to the lane each candidate's would
    change to of its own accord (:func:`hcomc.sim.step.lane_change.free_target`; on the
    paper's road the one other lane); ``force`` marks changes commanded by a merge plan,
    which are checked for safety only (like a ramp vehicle's).
    """
    cand = np.ascontiguousarray(cand, dtype=np.int64).reshape(-1)
    if cand.size == 0:
        return cand, cand
    lane = np.ascontiguousarray(lane, dtype=np.int64)
    if target is None:
        target = np.array([free_target(lanes.ints, int(code)) for code in lane], dtype=np.int64)
    force = np.zeros(cand.size, dtype=bool) if force is None else np.asarray(force, dtype=bool)
    ints, flags = np.empty((4, cand.size), dtype=np.int64), np.empty((2, cand.size), dtype=bool)
    m = mobil_decide_into(
        Traffic(fleet.matrix, fleet.iidm, fleet.length, snap.x, snap.v, snap.a,
                np.empty(snap.x.size), np.full(snap.x.size, NOT_KNOWN)),
        index,
        Candidates(cand, lane, _ints(leader), _ints(follower), _ints(target), force,
                   np.zeros(cand.size)),
        lane_change_params(params), lanes.ints,
        MobilWork(ints, flags, np.empty((2, snap.x.size)), np.empty(cand.size)),
    )  # fmt: skip
    return ints[0, :m].copy(), ints[1, :m].copy()


def lane_change_params(params: LaneChangeParams) -> FloatArray:
    """The MOBIL parameters as the kernel reads them."""
    return np.array(
        [params.min_gap, params.safe_decel, params.politeness, params.threshold,
         params.keep_right_bias, params.emergency_decel], dtype=np.float64,
    )  # fmt: skip


def _ints(a: IntArray) -> IntArray:
    return np.ascontiguousarray(a, dtype=np.int64).reshape(-1)
