"""Typed record of a merge plan as a run keeps it: ``SimulationLog.meta["plans"]``.

The log's metadata stays plain JSON (it is saved with the log and read by other tools);
:class:`PlanRecord` is the typed view of one entry, written by :meth:`PlanRecord.to_json`
and read back by :func:`plan_records`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

from hcomc.interface import MergePlan, Mode
from hcomc.road import KEY_ROLES

if TYPE_CHECKING:
    from hcomc._typing import FloatArray
    from hcomc.sim.log.simulation_log import SimulationLog

__all__ = ["PlanRecord", "plan_records"]

Cubic = tuple[float, float, float, float]
_MODES = tuple(m.name.lower() for m in Mode)
_SEQUENCES = ("ahead", "behind")


def _cubic(values: FloatArray | list[float] | None, name: str) -> Cubic | None:
    if values is None:
        return None
    c = tuple(float(v) for v in values)
    if len(c) != 4:
        raise ValueError(f"plan record key '{name}' = {list(c)}: allowed: 4 cubic coefficients")
    return (c[0], c[1], c[2], c[3])


@dataclass(frozen=True, slots=True)
class PlanRecord:
    """One merge plan as the run recorded it (all times absolute simulation time [s]).

    Attributes mirror :class:`hcomc.interface.MergePlan`: ``group`` (role -> vehicle
    index, -1 = missing), ``mode`` ("none", "longitudinal" or "lateral"), ``t0``,
    ``merge_x`` [m], ``vr_duration``, ``horizon``, the cubic coefficients ``vv0``, ``vv1``,
    ``vv2`` of the virtual vehicles (None when not planned), ``sequence`` ("ahead" or
    "behind"), ``fallback``, ``eq19_branch`` (HCOMC's Eq. 19 case, "" otherwise),
    ``reason``, ``objectives`` and ``decision_ms`` [ms].
    """

    group: dict[str, int]
    mode: str
    t0: float
    merge_x: float = math.nan
    vr_duration: float = math.nan
    horizon: float = math.nan
    vv1: Cubic | None = None
    vv2: Cubic | None = None
    sequence: str = "ahead"
    vv0: Cubic | None = None
    fallback: bool = False
    eq19_branch: str = ""
    reason: str = ""
    objectives: dict[str, float] = field(default_factory=dict)
    decision_ms: float = 0.0

    def __post_init__(self) -> None:
        if self.mode not in _MODES:
            raise ValueError(f"plan record key 'mode' = {self.mode!r}; allowed: {_MODES}")
        if self.sequence not in _SEQUENCES:
            raise ValueError(
                f"plan record key 'sequence' = {self.sequence!r}; allowed: {_SEQUENCES}"
            )
        unknown = set(self.group) - set(KEY_ROLES)
        if unknown or "VR" not in self.group:
            raise ValueError(
                f"plan record key 'group' = {self.group}; allowed: roles {KEY_ROLES} with VR"
            )

    def vehicle(self, role: str) -> int:
        """Vehicle index playing ``role`` (-1 if missing)."""
        return int(self.group.get(role, -1))

    @classmethod
    def from_plan(cls, plan: MergePlan) -> PlanRecord:
        """The record of a controller's plan."""
        return cls(
            group=plan.group.as_dict(),
            mode=Mode(plan.mode).name.lower(),
            t0=float(plan.t0),
            merge_x=float(plan.merge_x),
            vr_duration=float(plan.vr_duration),
            horizon=float(plan.horizon),
            vv1=_cubic(plan.vv1, "vv1"),
            vv2=_cubic(plan.vv2, "vv2"),
            sequence=plan.sequence,
            vv0=_cubic(plan.vv0, "vv0"),
            fallback=bool(plan.fallback),
            eq19_branch=plan.details.eq19_branch,
            reason=plan.reason,
            objectives={k: float(v) for k, v in plan.objectives.items()},
            decision_ms=float(plan.decision_ms),
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON-ready dict stored in ``SimulationLog.meta["plans"]``."""

        def cubic(c: Cubic | None) -> list[float] | None:
            return None if c is None else list(c)

        return {
            "group": dict(self.group),
            "mode": self.mode,
            "t0": self.t0,
            "merge_x": self.merge_x,
            "vr_duration": self.vr_duration,
            "horizon": self.horizon,
            "vv1": cubic(self.vv1),
            "vv2": cubic(self.vv2),
            "sequence": self.sequence,
            "vv0": cubic(self.vv0),
            "fallback": self.fallback,
            "eq19_branch": self.eq19_branch,
            "reason": self.reason,
            "objectives": dict(self.objectives),
            "decision_ms": self.decision_ms,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> PlanRecord:
        """Read one entry of ``meta["plans"]``; keys missing from older logs take defaults.

        Raises
        ------
        ValueError
            On an unknown key, a missing ``group``/``mode``/``t0`` or a bad value.
        """
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(f"plan record key '{unknown[0]}' unknown; allowed: {sorted(known)}")
        missing = [k for k in ("group", "mode", "t0") if k not in data]
        if missing:
            raise ValueError(f"plan record key '{missing[0]}' is missing")

        def number(key: str, default: float) -> float:
            value = data.get(key, default)
            return math.nan if value is None else float(value)

        return cls(
            group={str(role): int(k) for role, k in dict(data["group"]).items()},
            mode=str(data["mode"]),
            t0=float(data["t0"]),
            merge_x=number("merge_x", math.nan),
            vr_duration=number("vr_duration", math.nan),
            horizon=number("horizon", math.nan),
            vv1=_cubic(data.get("vv1"), "vv1"),
            vv2=_cubic(data.get("vv2"), "vv2"),
            sequence=str(data.get("sequence", "ahead")),
            vv0=_cubic(data.get("vv0"), "vv0"),
            fallback=bool(data.get("fallback", False)),
            eq19_branch=str(data.get("eq19_branch", "")),
            reason=str(data.get("reason", "")),
            objectives={str(k): float(v) for k, v in dict(data.get("objectives", {})).items()},
            decision_ms=number("decision_ms", 0.0),
        )


def plan_records(log: SimulationLog) -> list[PlanRecord]:
    """The typed plans of a run, in decision order (empty if it made none)."""
    return [PlanRecord.from_json(entry) for entry in log.meta.get("plans") or []]
