"""Identification of the six key vehicles around a ramp vehicle (Section II-A), compiled.

When a ramp vehicle (VR) enters the cooperative control zone, the engine identifies its key
vehicles with these kernels (on a traffic view: :mod:`hcomc.control.key_group`) and calls
``controller.plan(view, group, rng)`` (:mod:`hcomc.interface`); it replans in a receding
horizon — key vehicles re-identified, ``plan`` called again — every ``control.replan_period``
seconds until VR starts its lane change (or a lateral cooperation has begun), and falls back to
gap acceptance if the plan cannot be executed safely.

Key vehicles, with VR's position projected onto lane 1 (virtual-vehicle mapping at the same
x, Uno et al. 1999):

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

import numpy as np

from hcomc._jit import kernel
from hcomc.road import N_ROLES, VMC, VMF, VMR, VNF, VNR, VR


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
def key_vehicle_indices(
    x: np.ndarray, lane: np.ndarray, active: np.ndarray, vr: int, lane_1: int, lane_2: int
) -> np.ndarray:
    """The six key vehicles of Section II-A around ramp vehicle ``vr``, in role order VR, VMC,
    VMF, VMR, VNF, VNR (-1 = missing; rules in the module doc); ``lane_1`` is the code of the
    mainline lane VR merges into, ``lane_2`` of the lane beyond it (-1: none)."""
    out = np.full(N_ROLES, -1, dtype=np.int64)
    out[VR] = vr
    vmf, vmc = nearest_in_lane(x, lane, active, lane_1, x[vr], vr)
    out[VMF] = vmf
    if vmc < 0:
        return out
    out[VMC] = vmc
    out[VMR] = nearest_in_lane(x, lane, active, lane_1, x[vmc] - 1e-9, vmc)[1]
    if lane_2 >= 0:
        out[VNF], out[VNR] = nearest_in_lane(x, lane, active, lane_2, x[vmc], vmc)
    return out
