"""Executing merge plans: which vehicles are commanded, and their virtual leaders.

The engine owns all state; this module only reads it and tells the engine what to do:

* a CAV VR starts its lane change at the plan's merge position with the plan's duration, if
  the MOBIL safety criterion holds then; otherwise it keeps trying until 3 vehicle lengths
  before the acceleration-lane end and then falls back to gap acceptance (logged);
* longitudinal mode: a CAV VMC follows the nearer of its real leader and VV1 (Eq. 8-10),
  which is the cubic for t - t0 <= H and VR's projection onto lane 1 after that;
* lateral mode: a CAV VMC changes to lane 2 at the planning time if that is safe (else the
  plan falls back to VR's gap acceptance, logged); a CAV VNR follows the nearer of its real
  leader and VV2 (Eq. 11-13) for t - t0 <= H.

A plan ends when VR's merge completes or a key vehicle leaves the road. While it is active,
commanded vehicles make no discretionary (MOBIL) lane changes of their own.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.control.base import MergePlan, Mode
from hcomc.control.virtual_vehicle import cubic_state


@dataclass
class ActivePlan:
    """A plan being executed and its progress."""

    plan: MergePlan
    vr_commanded: bool
    vmc_commanded: bool
    vnr_commanded: bool
    vr_started: bool = False
    vmc_started: bool = False
    released: bool = False  # VR back on gap acceptance
    done: bool = False

    @property
    def vr(self) -> int:
        """VR's vehicle index."""
        return self.plan.group.vr


def commanded(plans: list[ActivePlan], n: int) -> BoolArray:
    """Vehicles a live plan commands (excluded from MOBIL decisions)."""
    mask = np.zeros(n, dtype=bool)
    for p in plans:
        g = p.plan.group
        if p.vr_commanded and not p.vr_started and not p.released:
            mask[g.vr] = True
        if p.vmc_commanded:
            mask[g.vmc] = True
        if p.vnr_commanded:
            mask[g.vnr] = True
    return mask


def virtual_leaders(
    plans: list[ActivePlan],
    t: float,
    x: FloatArray,
    v: FloatArray,
    a: FloatArray,
    length: FloatArray,
) -> tuple[IntArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """``(followers, x_vv, v_vv, a_vv, length_vv)`` of every virtual vehicle in force at t."""
    rows: list[tuple[int, float, float, float, float]] = []
    for p in plans:
        plan, g = p.plan, p.plan.group
        tau = t - plan.t0
        if p.vmc_commanded and plan.mode == Mode.LONGITUDINAL and plan.vv1 is not None:
            if tau <= plan.horizon:
                xv, vv, av = (float(q) for q in cubic_state(plan.vv1, tau))
            else:
                xv, vv, av = float(x[g.vr]), float(v[g.vr]), float(a[g.vr])
            rows.append((g.vmc, xv, vv, av, float(length[g.vr])))
        if p.vnr_commanded and plan.vv2 is not None and tau <= plan.horizon:
            xv, vv, av = (float(q) for q in cubic_state(plan.vv2, tau))
            rows.append((g.vnr, xv, vv, av, float(length[g.vmc])))
    if not rows:
        empty = np.empty(0)
        return np.empty(0, dtype=np.int64), empty, empty, empty, empty
    cols = list(zip(*rows, strict=True))
    return (np.array(cols[0], dtype=np.int64), *(np.array(c, dtype=np.float64) for c in cols[1:]))


def plan_record(plan: MergePlan) -> dict[str, Any]:
    """JSON-ready summary of a plan, stored in ``SimulationLog.meta["plans"]`` for plots."""

    def floats(values: FloatArray | None) -> list[float] | None:
        return None if values is None else [float(v) for v in values]

    return {
        "group": plan.group.as_dict(),
        "mode": Mode(plan.mode).name.lower(),
        "t0": float(plan.t0),
        "merge_x": float(plan.merge_x),
        "vr_duration": float(plan.vr_duration),
        "horizon": float(plan.horizon),
        "vv1": floats(plan.vv1),
        "vv2": floats(plan.vv2),
        "fallback": bool(plan.fallback),
        "reason": plan.reason,
        "objectives": dict(plan.objectives),
        "decision_ms": float(plan.decision_ms),
    }
