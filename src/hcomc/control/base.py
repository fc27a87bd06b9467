"""Merge-controller interface: read-only traffic view, key vehicles, MergePlan.

When a ramp vehicle (VR) enters the cooperative control zone, the engine identifies the six
key vehicles of Section II-A and calls ``controller.plan(view, group, rng)``; it replans in a
receding horizon — key vehicles re-identified, ``plan`` called again — every
``control.replan_period`` seconds until VR starts its lane change (or a lateral cooperation
has begun), and falls back to gap acceptance if the plan cannot be executed safely (see
:mod:`hcomc.sim.execution`). The plans being executed are in ``view.plans``, so a controller
can continue them. Controllers read the view and return a :class:`MergePlan`; they never write
simulation state.

Key vehicles (Section II-A), with VR's position projected onto lane 1 (virtual-vehicle
mapping at the same x, Uno et al. 1999):

* VMF, VMC — the lane-1 vehicles directly ahead of and behind the projection: VR is to merge
  between them, so VMC is the vehicle that must cooperate;
* VMR — the lane-1 vehicle behind VMC;
* VNF, VNR — the lane-2 vehicles directly ahead of and behind VMC.

A vehicle belongs to the lane its ``view.lane`` entry gives; a vehicle in a lane change
switches lane at the lateral midpoint of its change, so it is a key vehicle of one lane at a
time (``view.changing`` is not used here). A missing vehicle is -1. Without VMC there is no one
to cooperate (VR merges by gap acceptance); without VMF or VNF the road ahead is free (planners
use a phantom far ahead).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from enum import IntEnum
from typing import TYPE_CHECKING, Protocol

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.road import KEY_ROLES, N_ROLES, VMC, VMF, VMR, VNF, VNR, VR, Kind, Lane

if TYPE_CHECKING:
    from hcomc.config import ScenarioConfig
    from hcomc.sim.fleet import Fleet


_MAIN_1, _MAIN_2 = int(Lane.MAIN_1), int(Lane.MAIN_2)
_CAV = int(Kind.CAV)  # a plain int: an enum member's lookup costs more than the comparison


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
        return dict(zip(KEY_ROLES, self.as_array().tolist(), strict=True))


@dataclass(frozen=True, slots=True)
class TrafficView:
    """Read-only snapshot handed to a controller (arrays over all vehicle slots).

    Attributes
    ----------
    t : simulation time [s].
    x, v, a : (N,) front-bumper position [m], speed [m/s], acceleration [m/s^2].
    lane : (N,) current lane (:class:`hcomc.road.Lane`).
    active : (N,) vehicle is on the road.
    changing : (N,) vehicle is in a lane-change manoeuvre: between the start of its change
        and its arrival on the target lane's centre line (the engine: target lane differs
        from origin lane; SUMO co-simulation: off its origin lane or a change in progress).
        Its ``lane`` switches to the target at the lateral midpoint. Information for
        controllers; the key-vehicle rules go by ``lane`` alone.
    fleet : per-vehicle constants; config : the scenario.
    plans : the plans being executed.
    """

    t: float
    x: FloatArray
    v: FloatArray
    a: FloatArray
    lane: IntArray
    active: BoolArray
    changing: BoolArray
    fleet: Fleet
    config: ScenarioConfig
    plans: tuple[MergePlan, ...] = ()

    @classmethod
    def snapshot(
        cls,
        t: float,
        state: dict[str, np.ndarray],
        fleet: Fleet,
        config: ScenarioConfig,
        plans: tuple[MergePlan, ...] = (),
    ) -> TrafficView:
        """A read-only view of an engine's state: copies of the ``x, v, a, lane, active,
        changing`` arrays, frozen, so a controller can never write the simulation state."""

        def frozen(name: str) -> np.ndarray:
            out = np.array(state[name], copy=True)
            out.flags.writeable = False
            return out

        return cls(
            t=t, x=frozen("x"), v=frozen("v"), a=frozen("a"), lane=frozen("lane"),
            active=frozen("active"), changing=frozen("changing"), fleet=fleet, config=config,
            plans=plans,
        )  # fmt: skip

    def is_cav(self, i: int) -> bool:
        """Whether vehicle ``i`` exists (``i >= 0``; -1 is a missing key vehicle) and is a CAV."""
        return i >= 0 and bool(self.fleet.kind[i] == _CAV)

    def live_plan(self, vr: int) -> MergePlan | None:
        """The plan being executed for ramp vehicle ``vr``, if any."""
        return next((p for p in self.plans if p.group.vr == vr), None)


@dataclass(frozen=True, slots=True)
class PlanDetails:
    """Controller-specific extras of a plan, for reporting only (the engine never reads them).

    This base carries none; each controller that reports more subclasses it with typed fields
    (:class:`hcomc.control.hcomc.controller.HCOMCDetails`,
    :class:`hcomc.control.fifo.FIFODetails`, :class:`hcomc.control.merge_game.GameDetails`).
    """

    @property
    def eq19_branch(self) -> str:
        """The Eq. 19 case that picked the plan; "" when the controller does not apply Eq. 19."""
        return ""


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
    vv0 : (4,) cubic coefficients of VV0, VR's virtual leader on the ramp (a CAV VR follows it
        towards its target gap, then its future leader's projection), or None.
    vv1 : (4,) cubic coefficients of VV1 in τ = t - t0 (Eq. 9-10), or None.
    vv2 : (4,) cubic coefficients of VV2 (Eq. 12-13), or None.
    fallback : True when no feasible plan was found and the safe default applies.
    reason : short human-readable explanation.
    objectives : objective values of the chosen plan (safety, fuel, efficiency).
    decision_ms : wall time of the decision [ms].
    details : controller-specific extras (Pareto set, game outcome, …) for reporting: a
        :class:`PlanDetails` (subclass).
    sequence : merge sequence, "ahead" (VR in front of the vehicle that was VMC when the
        key vehicles were identified) or "behind" (VR between that VMC and VMR). ``group`` is
        the group the plan executes: for "behind" it is :func:`behind_group`, in which the
        vehicle behind VR's slot plays VMC (it cooperates) and the one ahead plays VMF.
    """

    group: MergeGroup
    mode: Mode
    t0: float
    merge_x: float = float("nan")
    vr_duration: float = float("nan")
    horizon: float = float("nan")
    vv0: FloatArray | None = None
    vv1: FloatArray | None = None
    vv2: FloatArray | None = None
    fallback: bool = False
    reason: str = ""
    objectives: dict[str, float] = field(default_factory=dict)
    decision_ms: float = 0.0
    details: PlanDetails = field(default_factory=PlanDetails)
    sequence: str = "ahead"

    @property
    def cooperating(self) -> int:
        """The mainline vehicle the plan commands to cooperate (``group.vmc`` when the mode is
        not NONE), -1 when it commands nobody on the mainline."""
        return self.group.vmc if self.mode != Mode.NONE else -1


def elapsed_ms(start: float) -> float:
    """Milliseconds since ``start`` (a :func:`time.perf_counter` value): a decision's time."""
    return (time.perf_counter() - start) * 1000.0


class MergeController(Protocol):
    """Plans the merge of one ramp vehicle."""

    name: str

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        """Decide how VR merges and how the key vehicles cooperate."""
        ...


@kernel
def nearest_in_lane(
    x: np.ndarray, lane: np.ndarray, active: np.ndarray, in_lane: int, x0: float, exclude: int
) -> tuple[int, int]:
    """Nearest vehicle ahead (x' > x0) and behind (x' <= x0) in lane ``in_lane``, -1 if none
    (ties: the lowest index); vehicle ``exclude`` is skipped.

    "In the lane" is ``lane == in_lane``: a changing vehicle counts in its origin lane up to
    the lateral midpoint of its change and in its target lane after it, never in both.
    """
    lead, follow = -1, -1
    x_lead, x_follow = np.inf, -np.inf
    for i in range(x.size):
        if i == exclude or not active[i] or lane[i] != in_lane:
            continue
        if x[i] > x0:
            if x[i] < x_lead:
                lead, x_lead = i, x[i]
        elif x[i] > x_follow:
            follow, x_follow = i, x[i]
    return lead, follow


@kernel
def key_vehicle_indices(x: np.ndarray, lane: np.ndarray, active: np.ndarray, vr: int) -> np.ndarray:
    """The six key vehicles of Section II-A around ramp vehicle ``vr``, in role order VR, VMC,
    VMF, VMR, VNF, VNR (-1 = missing; rules in the module doc)."""
    out = np.full(N_ROLES, -1, dtype=np.int64)
    out[VR] = vr
    vmf, vmc = nearest_in_lane(x, lane, active, _MAIN_1, x[vr], vr)
    out[VMF] = vmf
    if vmc < 0:
        return out
    out[VMC] = vmc
    out[VMR] = nearest_in_lane(x, lane, active, _MAIN_1, x[vmc] - 1e-9, vmc)[1]
    out[VNF], out[VNR] = nearest_in_lane(x, lane, active, _MAIN_2, x[vmc], vmc)
    return out


def _nearest(view: TrafficView, lane: int, x: float, exclude: int) -> tuple[int, int]:
    """:func:`nearest_in_lane` on a view."""
    lead, follow = nearest_in_lane(view.x, view.lane, view.active, int(lane), float(x), exclude)
    return int(lead), int(follow)


def find_key_vehicles(view: TrafficView, vr: int) -> MergeGroup:
    """The six key vehicles of Section II-A around ramp vehicle ``vr`` (rules in module doc)."""
    return MergeGroup(*key_vehicle_indices(view.x, view.lane, view.active, vr).tolist())


def behind_group(view: TrafficView, group: MergeGroup) -> MergeGroup:
    """Relabelled key group for "VR merges behind VMC" (the old VMR cooperates).

    The vehicle ahead of VR's slot (old VMC) becomes ``vmf``, the vehicle behind it (old VMR)
    becomes ``vmc``, the lane-1 vehicle behind the old VMR becomes ``vmr`` and VNF/VNR are the
    lane-2 neighbours of the old VMR (the rules of :func:`find_key_vehicles`). Without an old
    VMR only ``vr`` and ``vmf`` are set (nobody to cooperate). Requires ``group.vmc >= 0``.
    """
    if group.vmc < 0:
        raise ValueError("behind_group needs a VMC (the vehicle VR merges behind)")
    new_vmc = group.vmr
    if new_vmc < 0:
        return MergeGroup(vr=group.vr, vmf=group.vmc)
    _, vmr = _nearest(view, Lane.MAIN_1, float(view.x[new_vmc]) - 1e-9, new_vmc)
    vnf, vnr = _nearest(view, Lane.MAIN_2, float(view.x[new_vmc]), new_vmc)
    return MergeGroup(vr=group.vr, vmc=new_vmc, vmf=group.vmc, vmr=vmr, vnf=vnf, vnr=vnr)


def virtual_states(
    plan: MergePlan, t: float, x: FloatArray, v: FloatArray, a: FloatArray
) -> dict[str, tuple[float, float, float]]:
    """State (x, v, a) at time t of each virtual vehicle ``plan`` has ("vv0", "vv1", "vv2").

    Within the horizon a virtual vehicle is its cubic; after it, VV0 is the projection of VR's
    future leader (``group.vmf``, if any) and VV1 that of VR; VV2 ends at the horizon. The
    engine executes exactly these, and a replanning controller continues them.
    """
    from hcomc.control.virtual_vehicle import cubic_state

    g, tau = plan.group, t - plan.t0
    out: dict[str, tuple[float, float, float]] = {}
    after = {"vv0": g.vmf, "vv1": g.vr, "vv2": -1}
    for name, coeffs in (("vv0", plan.vv0), ("vv1", plan.vv1), ("vv2", plan.vv2)):
        if coeffs is None:
            continue
        if tau <= plan.horizon:
            xv, vv, av = cubic_state(coeffs, tau)
            out[name] = (float(xv), float(vv), float(av))
        elif after[name] >= 0:
            j = after[name]
            out[name] = (float(x[j]), float(v[j]), float(a[j]))
    return out
