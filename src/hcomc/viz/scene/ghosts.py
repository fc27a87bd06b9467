"""The virtual vehicles of the plans in a run (Section III-A, Eqs. 8-9) as the top-down scene
(:mod:`hcomc.viz.scene.frame`) shows them: ghosts in a fixed lane, each in force from its plan's
start until its horizon ends or a replan of the same VR replaces it."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from hcomc.viz.scene.road import SceneRoad

__all__ = ["Ghost", "plan_ghosts"]

# Coefficients (c0, c1, c2, c3) of a virtual vehicle's cubic x(τ) (Section III-A, Eqs. 8-9).
Cubic = tuple[float, float, float, float]


@dataclass(frozen=True)
class Ghost:
    """One virtual vehicle of a plan: cubic x(τ) in a fixed lane while the plan is in force
    (from its t0 until its horizon ends or a replan of the same VR replaces it)."""

    label: str
    coefficients: Cubic
    t0: float
    horizon: float
    until: float
    y: float
    length: float
    width: float

    def x_at(self, t: float) -> float | None:
        """Position [m] at time *t* [s], or None outside ``[t0, min(t0 + horizon, until))``."""
        tau = t - self.t0
        if not (0.0 <= tau <= self.horizon and t < self.until):
            return None
        b1, b2, b3, b4 = self.coefficients
        return b1 + tau * (b2 + tau * (b3 + tau * b4))


def plan_ghosts(
    meta: Mapping[str, Any], lengths: np.ndarray, widths: np.ndarray, road: SceneRoad
) -> list[Ghost]:
    """Virtual vehicles of every plan in ``meta["plans"]``, each until the next plan of its VR."""
    ghosts: list[Ghost] = []
    plans = list(meta.get("plans") or [])
    for i, plan in enumerate(plans):
        group = plan.get("group") or {}
        later = [
            float(p["t0"])
            for p in plans[i + 1 :]
            if (p.get("group") or {}).get("VR") == group.get("VR") and p.get("t0") is not None
        ]
        until = min(later, default=math.inf)
        for label, key, lane_y, owner in (
            ("VV0", "vv0", -road.lane_width, "VMF"),
            ("VV1", "vv1", 0.0, "VR"),
            ("VV2", "vv2", road.lane_width, "VMC"),
        ):
            coefficients = plan.get(key)
            if coefficients is None or plan.get("horizon") is None or plan.get("t0") is None:
                continue
            owner_k = group.get(owner)
            k = -1 if owner_k is None else int(owner_k)
            valid = 0 <= k < lengths.size
            ghosts.append(
                Ghost(
                    label=label,
                    coefficients=cast(Cubic, tuple(float(c) for c in coefficients)),
                    t0=float(plan["t0"]),
                    horizon=float(plan["horizon"]),
                    until=until,
                    y=lane_y,
                    length=float(lengths[k]) if valid else road.vehicle_length,
                    width=float(widths[k]) if valid else road.vehicle_width,
                )
            )
    return ghosts
