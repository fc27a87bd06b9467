"""Every merge plan is checked before the engine executes it.

A controller — built in or a researcher's own class — returns a :class:`MergePlan`, and the
engines (:mod:`hcomc.sim.engine`, the SUMO co-simulation) execute it from a table of numbers
without asking what they mean: a longitudinal plan without VV1, a merge position past the lane
end or ``vr_duration = -1`` (VR never merges) would run without complaint. So both engines
pass each plan through :func:`checked`, which applies :func:`check_plan`.

The rules are those the execution relies on (:mod:`hcomc.sim.plan_execution`,
:mod:`hcomc.sim.step.plans`), one small function each below; every built-in controller meets
them. The structure of every plan: a :class:`MergePlan` with a :class:`Mode`, for this VR, its
group the key group of its sequence, ``t0`` the planning time. A fallback plan (the safe
default) must command nobody; its other numbers are for reporting (FIFO and Game keep the
horizon they tried) and are not checked. Any other plan: numbers finite where used and within
bounds taken from the config, each virtual vehicle in the mode that executes it, and only CAVs
of the group commanded. A finite ``merge_x`` for an HDV VR is allowed: FIFO, Game and HCOMC
report their merge position for every VR, and the engine ignores it (it commands CAVs only).

A broken rule raises :class:`InvalidPlan` naming the field, its value and what is allowed; with
``control.on_invalid_plan = "fallback"`` :func:`checked` returns the safe default instead (VR
merges by gap acceptance) with the broken rule in its ``reason``. A controller that raises
while planning is reported the same way: :func:`planned`, the engines' one call of a plan,
turns the exception into :class:`ControllerFailed` naming the controller, VR, time and run.
"""

from __future__ import annotations

import math
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import TypeGuard

import numpy as np

from hcomc.config.vehicle_tables import IDMParams
from hcomc.control.key_group import behind_group
from hcomc.interface import MergeController, MergeGroup, MergePlan, Mode, TrafficView
from hcomc.road import KEY_ROLES

__all__ = ["ControllerFailed", "InvalidPlan", "check_plan", "checked", "name_of", "planned"]

SEQUENCES = ("ahead", "behind")
CUBICS = ("vv0", "vv1", "vv2")


class InvalidPlan(ValueError):  # noqa: N818 (reads as what it reports: an invalid plan)
    """A controller returned a plan the engine must not execute.

    Attributes: ``field`` (of the plan: ``"merge_x"``, ``"group.vmc"``, ...), its ``value``,
    ``allowed`` (in words); ``controller``, ``vr`` and ``t`` [s]: who planned for whom when.
    """

    def __init__(
        self, field: str, value: object, allowed: str, controller: str, vr: int, t: float
    ) -> None:
        self.field, self.value, self.allowed = field, value, allowed
        self.controller, self.vr, self.t = controller, vr, t
        super().__init__(f"controller '{controller}' returned an invalid plan for VR {vr} "
                         f"at t = {t:.10g} s: {self.rule}")  # fmt: skip

    def __reduce__(self) -> tuple[type[InvalidPlan], tuple[object, ...]]:
        """Pickled with its attributes (a run in a worker process raises it)."""
        args = (self.field, self.value, self.allowed, self.controller, self.vr, self.t)
        return type(self), args

    @property
    def rule(self) -> str:
        """``field = value; allowed: ...`` on one line."""
        return f"{self.field} = {_show(self.value)}; allowed: {self.allowed}"


class ControllerFailed(RuntimeError):  # noqa: N818 (reads as what happened)
    """A controller raised while planning.

    Attributes: ``controller``, ``vr`` and ``t`` [s]: who planned for whom when; ``where``:
    the run (its scenario and seed); ``error``: what the controller raised, its type and
    message on one line; ``trace``: that exception's traceback as text (text survives the
    trip out of a worker process, where the exception itself is re-created without it).
    """

    def __init__(
        self, controller: str, vr: int, t: float, where: str, error: str, trace: str
    ) -> None:
        self.controller, self.vr, self.t = controller, vr, t
        self.where, self.error, self.trace = where, error, trace
        super().__init__(f"controller '{controller}' raised {error} while planning for VR {vr} "
                         f"at t = {t:.10g} s ({where})")  # fmt: skip

    def __reduce__(self) -> tuple[type[ControllerFailed], tuple[object, ...]]:
        """Pickled with its attributes (a run in a worker process raises it)."""
        args = (self.controller, self.vr, self.t, self.where, self.error, self.trace)
        return type(self), args


def planned(
    controller: MergeController,
    view: TrafficView,
    group: MergeGroup,
    rng: np.random.Generator,
    where: str,
) -> MergePlan:
    """``controller.plan(view, group, rng)``, the one call of a controller's plan every engine
    makes; an exception the controller raises becomes :class:`ControllerFailed`, naming the
    controller, VR, time and ``where`` (the run: scenario and seed)."""
    try:
        return controller.plan(view, group, rng)
    except Exception as exc:
        message = " ".join(str(exc).split())
        error = f"{type(exc).__name__}: {message}" if message else type(exc).__name__
        raise ControllerFailed(
            name_of(controller), group.vr, float(view.t), where, error, traceback.format_exc()
        ) from exc


def _show(value: object) -> str:
    """A value on one line."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, Enum):
        return f"{type(value).__name__}.{value.name}"
    return " ".join(repr(value).split())


# ------------------------------------------------------------------------- bounds
@dataclass(frozen=True)
class Interval:
    """Allowed numbers between ``low`` and ``high``, each end open or closed."""

    low: float
    high: float
    low_open: bool = False
    high_open: bool = False

    def holds(self, x: float) -> bool:
        """Whether ``x`` lies in the interval (NaN never does)."""
        above = x > self.low if self.low_open else x >= self.low
        return bool(above and (x < self.high if self.high_open else x <= self.high))

    def __str__(self) -> str:
        left, right = "(" if self.low_open else "[", ")" if self.high_open else "]"
        return f"{left}{self.low:g}, {self.high:g}{right}"


def merge_positions(view: TrafficView) -> Interval:
    """Where VR may start its lane change: the acceleration lane [m]. Past its end VR (not
    braking for the lane end while it follows its plan) would drive off the lane."""
    return Interval(view.ramp.accel_lane_start, view.ramp.accel_lane_end)


def lane_change_durations() -> Interval:
    """VR's lane-change duration [s]: the schema's bounds of ``lane_change_duration``."""
    meta = IDMParams.model_fields["lane_change_duration"].metadata
    b = {k: float(v) for m in meta for k in ("gt", "ge", "lt", "le")
         if (v := getattr(m, k, None)) is not None}  # fmt: skip
    return Interval(b.get("gt", b.get("ge", -math.inf)), b.get("lt", b.get("le", math.inf)),
                    low_open="gt" in b, high_open="lt" in b)  # fmt: skip


def horizons(view: TrafficView) -> Interval:
    """The virtual-vehicle horizon H [s]: positive, at most ``control.horizon_max``."""
    return Interval(0.0, view.config.control.horizon_max, low_open=True)


def time_tolerance(view: TrafficView) -> float:
    """How far ``t0`` may be from the planning time [s]: half a step ``dt`` (the same step)."""
    return 0.5 * view.config.dt


# -------------------------------------------------------------------------- rules
Problem = tuple[str, object, str] | None
"""What a rule found: (field, value, allowed), or None."""
Rule = Callable[[MergePlan, TrafficView, MergeGroup], Problem]


def _number(x: object) -> TypeGuard[float | int | np.integer | np.floating]:
    return isinstance(x, float | int | np.integer | np.floating) and not isinstance(x, bool)


def _nan(x: object) -> bool:
    return _number(x) and math.isnan(float(x))


def _commands_vr(plan: MergePlan, view: TrafficView) -> bool:
    """The engine commands VR (VV0, its change at ``merge_x``) if a CAV with a ``merge_x``."""
    return view.is_cav(plan.group.vr) and _number(plan.merge_x) and not _nan(plan.merge_x)


def _number_rule(
    field: str, value: object, bounds: Interval, what: str, nan: str | None, why: str = ""
) -> Problem:
    """``value`` is a number in ``bounds`` or, when ``nan`` says what it means, NaN."""
    if _number(value) and (bounds.holds(float(value)) or (nan is not None and _nan(value))):
        return None
    either = f"NaN ({nan}) or " if nan is not None else ""
    return field, value, f"{either}{what} {bounds}{why}"


def _structure(plan: MergePlan, view: TrafficView, group: MergeGroup) -> Problem:
    """A mode and a group for this VR, a known sequence, ``t0`` the planning time."""
    if not isinstance(plan.mode, Mode):
        return "mode", plan.mode, "a hcomc.interface.Mode (NONE, LONGITUDINAL, LATERAL)"
    if not isinstance(plan.group, MergeGroup):
        return "group", plan.group, "a hcomc.interface.MergeGroup"
    if plan.group.vr != group.vr:
        return "group.vr", plan.group.vr, f"{group.vr}, the ramp vehicle planned for"
    if plan.sequence not in SEQUENCES or (plan.sequence == "behind" and group.vmc < 0):
        return "sequence", plan.sequence, "'ahead' or 'behind' ('behind' only with a VMC)"
    tol = time_tolerance(view)  # the cubics run in t - t0
    if not (_number(plan.t0) and abs(float(plan.t0) - view.t) <= tol):
        return "t0", plan.t0, f"the planning time view.t = {view.t:.10g} s (within {tol:g} s)"
    return None


def _roles(plan: MergePlan, view: TrafficView, group: MergeGroup) -> Problem:
    """The plan's group is its sequence's key group, role by role: the engine takes every
    role from it (VMC follows VV1, VNR follows VV2, VMF leads VR after the horizon)."""
    behind = plan.sequence == "behind"
    expected = behind_group(view, group) if behind else group
    which = "behind_group(view, group)" if behind else "the key group"
    for role, got, want in zip(KEY_ROLES, plan.group.as_array(), expected.as_array(), strict=True):
        if got != want:
            return f"group.{role.lower()}", int(got), f"{want}, {role} of {which}"
    return None


def _safe_default(plan: MergePlan, view: TrafficView, group: MergeGroup) -> Problem:
    """A fallback plan commands nobody: VR merges by gap acceptance, no virtual vehicle."""
    if plan.mode != Mode.NONE:
        return "mode", plan.mode, "Mode.NONE in a fallback plan (it commands nobody)"
    if not _nan(plan.merge_x):
        return "merge_x", plan.merge_x, "NaN in a fallback plan (VR merges by gap acceptance)"
    cubic = next((name for name in CUBICS if getattr(plan, name) is not None), None)
    if cubic is not None:
        return cubic, getattr(plan, cubic), "None in a fallback plan (it commands nobody)"
    return None


def _numbers(plan: MergePlan, view: TrafficView, group: MergeGroup) -> Problem:
    """Merge position, VR's duration (needed when VR is commanded: the SUMO co-simulation
    sets its lateral speed from it) and horizon (needed by any virtual vehicle)."""
    cav_vr = _commands_vr(plan, view)
    virtual = [name for name in CUBICS if getattr(plan, name) is not None]
    return (
        _number_rule("merge_x", plan.merge_x, merge_positions(view),
                     "a position within the acceleration lane", "gap acceptance", " m")
        or _number_rule("vr_duration", plan.vr_duration, lane_change_durations(),
                        "a lane-change duration in", None if cav_vr else "not commanded",
                        " s (VR is a CAV with a finite merge_x)" if cav_vr else " s")
        or _number_rule("horizon", plan.horizon, horizons(view), "a horizon in",
                        None if virtual else "no virtual vehicle",
                        f" s (the plan has {', '.join(virtual)})" if virtual else " s")
    )  # fmt: skip


def _cubic(value: object) -> bool:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        return False
    return array.shape == (4,) and bool(np.isfinite(array).all())


def _virtual_vehicles(plan: MergePlan, view: TrafficView, group: MergeGroup) -> Problem:
    """Each virtual vehicle None or four finite cubic coefficients, and in the plan that
    executes it: VV1 in longitudinal mode (which needs it), VV2 in lateral mode, VV0 for a
    commanded VR."""
    bad = next(
        (n for n in CUBICS if getattr(plan, n) is not None and not _cubic(getattr(plan, n))), None
    )
    if bad is not None:
        return bad, getattr(plan, bad), "None or 4 finite cubic coefficients, shape (4,)"
    mode = plan.mode.name
    if plan.mode == Mode.LONGITUDINAL and plan.vv1 is None:
        return "vv1", None, "VV1's 4 cubic coefficients (longitudinal mode: VMC follows VV1)"
    if plan.mode != Mode.LONGITUDINAL and plan.vv1 is not None:
        return "vv1", plan.vv1, f"None (VV1 acts in longitudinal mode only; mode is {mode})"
    if plan.vv2 is not None and plan.mode != Mode.LATERAL:
        return "vv2", plan.vv2, f"None (VV2 belongs to lateral mode; mode is {mode})"
    if plan.vv0 is not None and not _commands_vr(plan, view):
        return "vv0", plan.vv0, "None unless VR is a CAV with a finite merge_x (VV0 leads it)"
    return None


def _commanded_cavs(plan: MergePlan, view: TrafficView, group: MergeGroup) -> Problem:
    """Only CAVs are commanded: the cooperating vehicle (mode not NONE), VNR (with a VV2)."""
    vmc, vnr = plan.group.vmc, plan.group.vnr
    if plan.mode != Mode.NONE and not view.is_cav(vmc):
        kind = "missing" if vmc < 0 else "an HDV"
        return "group.vmc", vmc, f"a CAV in mode {plan.mode.name} (VMC is {kind}), or Mode.NONE"
    if plan.vv2 is not None and not view.is_cav(vnr):
        kind = "missing" if vnr < 0 else "an HDV"
        return "vv2", plan.vv2, f"None: VV2 commands VNR, which is {kind}"
    return None


STRUCTURE: tuple[Rule, ...] = (_structure, _roles)
"""Rules of every plan, in the order checked."""
CONTENT: tuple[Rule, ...] = (_numbers, _virtual_vehicles, _commanded_cavs)
"""Rules of a plan that is not a fallback, in the order checked."""


def check_plan(plan: object, view: TrafficView, group: MergeGroup, controller_name: str) -> None:
    """Raise :class:`InvalidPlan` for the first rule (module doc) ``plan`` breaks; ``group``
    is the key group the controller was asked to plan for."""
    if not isinstance(plan, MergePlan):
        found: Problem = ("plan", type(plan).__name__, "a hcomc.interface.MergePlan")
    else:
        rules = (*STRUCTURE, _safe_default) if plan.fallback else (*STRUCTURE, *CONTENT)
        found = next((p for p in (rule(plan, view, group) for rule in rules) if p), None)
    if found is not None:
        raise InvalidPlan(*found, controller=controller_name, vr=group.vr, t=view.t)


def checked(
    plan: MergePlan, view: TrafficView, group: MergeGroup, controller_name: str
) -> MergePlan:
    """``plan`` if it passes :func:`check_plan`, else as ``control.on_invalid_plan`` (of
    ``view.config``) says: raise the :class:`InvalidPlan` ("error"), or return the safe
    default ("fallback": mode NONE, ``fallback=True``, VR merges by gap acceptance; the engine
    logs a FALLBACK event and the plan record keeps the broken rule in ``reason``)."""
    try:
        check_plan(plan, view, group, controller_name)
    except InvalidPlan as error:
        if view.config.control.on_invalid_plan == "error":
            raise
        why = f"invalid plan from '{controller_name}': {error.rule}; VR merges by gap acceptance"
        spent = plan.decision_ms if isinstance(plan, MergePlan) else 0.0
        return MergePlan(group, Mode.NONE, view.t, fallback=True, reason=why, decision_ms=spent)
    return plan


def name_of(controller: object) -> str:
    """A controller's name for messages: its ``name``, else its class name."""
    return str(getattr(controller, "name", None) or type(controller).__name__)
