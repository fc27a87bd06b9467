"""Merge-controller interface: read-only traffic view, key vehicles, MergePlan.

When a ramp vehicle (VR) enters the cooperative control zone, the engine identifies the six
key vehicles of Section II-A and calls ``controller.plan(view, group, rng)`` once (the replanning
policy: one plan per VR; the engine falls back to gap acceptance if the plan cannot be executed
safely, see :mod:`hcomc.sim.execution`). Controllers read the view and return a
:class:`MergePlan`; they never write simulation state.

Key vehicles (Section II-A), with VR's position projected onto lane 1 (virtual-vehicle
mapping at the same x, Uno et al. 1999):

* VMF, VMC — the lane-1 vehicles directly ahead of and behind the projection: VR is to merge
  between them, so VMC is the vehicle that must cooperate;
* VMR — the lane-1 vehicle behind VMC;
* VNF, VNR — the lane-2 vehicles directly ahead of and behind VMC.

A missing vehicle is -1. Without VMC there is no one to cooperate (VR merges by gap
acceptance); without VMF or VNF the road ahead is free (planners use a phantom far ahead).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from enum import IntEnum
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.sim.road import Lane

if TYPE_CHECKING:
    from hcomc.config import ScenarioConfig
    from hcomc.sim.fleet import Fleet


class Mode(IntEnum):
    """VMC's cooperation mode."""

    NONE = 0
    LONGITUDINAL = 1
    LATERAL = 2


@dataclass(frozen=True, slots=True)
class MergeGroup:
    """Vehicle indices of the six key vehicles (-1 = missing)."""

    vr: int
    vmc: int = -1
    vmf: int = -1
    vmr: int = -1
    vnf: int = -1
    vnr: int = -1

    def as_array(self) -> IntArray:
        """Indices in role order VR, VMC, VMF, VMR, VNF, VNR."""
        return np.array([self.vr, self.vmc, self.vmf, self.vmr, self.vnf, self.vnr])

    def as_dict(self) -> dict[str, int]:
        """Role name -> vehicle index."""
        return dict(
            zip(("VR", "VMC", "VMF", "VMR", "VNF", "VNR"), self.as_array().tolist(), strict=True)
        )


@dataclass(frozen=True, slots=True)
class TrafficView:
    """Read-only snapshot handed to a controller (arrays over all vehicle slots)."""

    t: float
    x: FloatArray
    v: FloatArray
    a: FloatArray
    lane: IntArray
    active: BoolArray
    changing: BoolArray
    fleet: Fleet
    config: ScenarioConfig


@dataclass(frozen=True)
class MergePlan:
    """A controller's decision for one VR (all times absolute simulation time [s]).

    Attributes
    ----------
    group : the key vehicles.
    mode : VMC's cooperation mode.
    t0 : planning time [s].
    merge_x : position where a CAV VR starts its lane change [m] (NaN: gap acceptance).
    vr_duration : VR's lane-change duration [s].
    horizon : virtual-vehicle horizon H = tf' - t0' [s].
    vv1 : (4,) cubic coefficients of VV1 in τ = t - t0 (Eq. 9-10), or None.
    vv2 : (4,) cubic coefficients of VV2 (Eq. 12-13), or None.
    fallback : True when no feasible plan was found and the safe default applies.
    reason : short human-readable explanation.
    objectives : objective values of the chosen plan (safety, fuel, efficiency).
    decision_ms : wall time of the decision [ms].
    details : controller-specific extras (Pareto set, game outcome, …) for reporting.
    sequence : merge sequence, "ahead" (VR between VMF and VMC) or "behind" (VR between VMC
        and VMR), with the roles of the key group found at planning time.
    """

    group: MergeGroup
    mode: Mode
    t0: float
    merge_x: float = float("nan")
    vr_duration: float = float("nan")
    horizon: float = float("nan")
    vv1: FloatArray | None = None
    vv2: FloatArray | None = None
    fallback: bool = False
    reason: str = ""
    objectives: dict[str, float] = field(default_factory=dict)
    decision_ms: float = 0.0
    details: dict[str, Any] = field(default_factory=dict)
    sequence: str = "ahead"


def elapsed_ms(start: float) -> float:
    """Milliseconds since ``start`` (a :func:`time.perf_counter` value): a decision's time."""
    return (time.perf_counter() - start) * 1000.0


class MergeController(Protocol):
    """Plans the merge of one ramp vehicle."""

    name: str

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        """Decide how VR merges and how the key vehicles cooperate."""
        ...


def _nearest(view: TrafficView, lane: int, x: float, exclude: int) -> tuple[int, int]:
    """Nearest vehicle ahead (x' > x) and behind (x' <= x) in ``lane``, -1 if none.

    A vehicle changing into or out of ``lane`` counts as in it (it occupies both lanes).
    """
    in_lane = view.active & (view.lane == lane)
    in_lane[exclude] = False
    idx = np.flatnonzero(in_lane)
    ahead, behind = idx[view.x[idx] > x], idx[view.x[idx] <= x]
    lead = int(ahead[np.argmin(view.x[ahead])]) if ahead.size else -1
    follow = int(behind[np.argmax(view.x[behind])]) if behind.size else -1
    return lead, follow


def find_key_vehicles(view: TrafficView, vr: int) -> MergeGroup:
    """The six key vehicles of Section II-A around ramp vehicle ``vr`` (rules in module doc)."""
    vmf, vmc = _nearest(view, Lane.MAIN_1, view.x[vr], vr)
    if vmc < 0:
        return MergeGroup(vr=vr, vmf=vmf)
    _, vmr = _nearest(view, Lane.MAIN_1, view.x[vmc] - 1e-9, vmc)
    vnf, vnr = _nearest(view, Lane.MAIN_2, view.x[vmc], vmc)
    return MergeGroup(vr=vr, vmc=vmc, vmf=vmf, vmr=vmr, vnf=vnf, vnr=vnr)
