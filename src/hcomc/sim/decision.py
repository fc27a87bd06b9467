"""One decision of the merge controller, as every engine takes it, with its step listeners.

A ramp vehicle VR is decided for when it enters the control zone and again whenever its
plan is due for a replan (or a listener asks, :meth:`StepListener.decisions_due`). The key
vehicles are found on the true state (so every controller is judged on the same vehicles);
the controller plans on the view its listeners let it see (:meth:`StepListener.view`, e.g.
what a V2X channel delivered) and gets the safe default when a key vehicle is missing
from that view; the plan is checked (:func:`hcomc.control.validation.checked`), recorded,
and put into force by the engine now, unless a listener took it on its way
(:meth:`StepListener.send`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from hcomc._typing import BoolArray
from hcomc.control.key_group import find_key_vehicles
from hcomc.control.validation import checked, name_of, planned
from hcomc.interface import MergeController, MergeGroup, MergePlan, Mode, TrafficView
from hcomc.interface.listener import ListenedRun, StepListener
from hcomc.sim.plan_execution import DecisionRecorder, record_decision

__all__ = ["DecidingRun", "decide", "undecided"]


class DecidingRun(ListenedRun, DecisionRecorder, Protocol):
    """An engine as :func:`decide` uses it."""

    controller: MergeController | None
    listeners: Sequence[StepListener]
    rng: np.random.Generator
    planned: BoolArray

    def view(self, t: float, vr: int, /) -> TrafficView:
        """The true state at ``t`` as a controller deciding for ramp vehicle ``vr`` reads
        it."""
        ...


def undecided(run: DecidingRun, vrs: Sequence[int]) -> list[int]:
    """``vrs`` less those a listener holds (their last plan is on its way) and repeats."""
    return [vr for vr in dict.fromkeys(vrs)
            if not any(listener.holds(vr) for listener in run.listeners)]  # fmt: skip


def decide(run: DecidingRun, vr: int, t: float, where: str) -> MergePlan:
    """Decide for ramp vehicle ``vr`` at ``t`` (``where``: the run, for the message of a
    controller that fails), record the decision and send its plan; returns the plan."""
    assert run.controller is not None
    run.planned[vr] = True
    view = run.view(t, vr)
    group = find_key_vehicles(view, vr)
    for listener in run.listeners:
        view = listener.view(run, view)
    plan = _missing_key_vehicles(view, group)
    if plan is None:
        plan = planned(run.controller, view, group, run.rng.spawn(1)[0], where)
    plan = checked(plan, view, group, name_of(run.controller))
    record_decision(run, view, group, plan, t)
    ident = len(run.decisions) - 1
    now = [listener.send(run, plan, ident, t) for listener in run.listeners]
    if all(now):
        run.execute(plan, ident)
    return plan


def _missing_key_vehicles(view: TrafficView, group: MergeGroup) -> MergePlan | None:
    """The safe default (mode NONE: VR merges by gap acceptance) when a key vehicle is not
    in the controller's view (never heard over the channel); None when all are."""
    missing = [int(i) for i in group.as_array() if i >= 0 and not view.active[i]]
    if not missing:
        return None
    return MergePlan(group, Mode.NONE, view.t, fallback=True,
                     reason=f"no V2X message from vehicles {missing}")  # fmt: skip
