"""What a merge controller decides: the key vehicles (MergeGroup), VMC's cooperation mode and
the plan for one ramp vehicle (MergePlan).

Key vehicles (Section II-A), with VR's position projected onto lane 1 (virtual-vehicle
mapping at the same x, Uno et al. 1999): VMF and VMC are the lane-1 vehicles directly ahead
of and behind the projection (VR merges between them, so VMC is the vehicle that must
cooperate), VMR the lane-1 vehicle behind VMC, VNF and VNR the lane-2 vehicles directly ahead
of and behind VMC. :mod:`hcomc.control.key_vehicles` identifies them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.road import KEY_ROLES


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

    def as_tuple(self) -> tuple[int, int, int, int, int, int]:
        """Indices in role order VR, VMC, VMF, VMR, VNF, VNR."""
        return (self.vr, self.vmc, self.vmf, self.vmr, self.vnf, self.vnr)

    def as_array(self) -> IntArray:
        """Indices in role order VR, VMC, VMF, VMR, VNF, VNR."""
        return np.array(self.as_tuple())

    def as_dict(self) -> dict[str, int]:
        """Role name -> vehicle index."""
        return dict(zip(KEY_ROLES, self.as_tuple(), strict=True))


@dataclass(frozen=True, slots=True)
class PlanDetails:
    """Controller-specific extras of a plan, for reporting only (the engine never reads them).

    This base carries none; each controller that reports more subclasses it with typed fields
    (:class:`hcomc.control.hierarchical.controller.HCOMCDetails`,
    :class:`hcomc.control.fifo.FIFODetails`,
    :class:`hcomc.control.merge_game.controller.GameDetails`).
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
        the group the plan executes: for "behind" it is
        :func:`~hcomc.control.key_group.behind_group`, in which the vehicle behind VR's
        slot plays VMC (it cooperates) and the one ahead plays VMF.
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
