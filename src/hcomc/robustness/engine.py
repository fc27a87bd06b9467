"""A scenario run with a V2X channel, an injected fault and a safety shield.

:class:`FaultedSimulation` is the engine's :class:`~hcomc.sim.engine.Simulation` with three
additions between its steps, all on the Python side of the engine's own hooks (outside
commands, the plan table, per-vehicle parameters), so the compiled step is the nominal
one:

* the controller plans on the channel's view (:class:`hcomc.robustness.channel.ChannelView`)
  and its plan is executed when it arrives, or never; a ramp vehicle whose plan was lost
  keeps the plan it had (none: it merges by gap acceptance) and is planned again a replan
  period later; a CAV whose CAV leader's messages are older than ``stale_after`` drives
  with the degraded time headway until they are fresh again;
* the fault of :class:`hcomc.robustness.settings.FaultParams`, timed from the ramp
  vehicle's control-zone entry;
* the shield of :mod:`hcomc.robustness.shield`.

From the end of the warm-up the run advances one step at a time (a step taken from Python
equals a compiled one), so with the ideal channel, no fault and no shield it is the
scenario's nominal run, bit for bit.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.control.base import MergeController, MergePlan, Mode, find_key_vehicles
from hcomc.control.validation import checked, name_of
from hcomc.road import Kind, Lane
from hcomc.robustness.impairments import Impairments
from hcomc.robustness.settings import ChannelParams, FaultParams, ShieldParams
from hcomc.robustness.shield import commanded_vehicles
from hcomc.sim import core
from hcomc.sim import core_state as layout
from hcomc.sim.core_plans import add_plan, encode_plan
from hcomc.sim.engine import Simulation
from hcomc.sim.execution import plan_record
from hcomc.sim.log import EventKind, SimulationLog

__all__ = ["FaultedSimulation"]


class FaultedSimulation(Impairments, Simulation):
    """One run of ``config`` with ``seed`` under ``channel``, ``fault`` and ``shield``."""

    def __init__(
        self,
        config: ScenarioConfig,
        seed: int | None = None,
        controller: MergeController | None = None,
        *,
        channel: ChannelParams | None = None,
        fault: FaultParams | None = None,
        shield: ShieldParams | None = None,
    ) -> None:
        super().__init__(config, seed, controller)
        self._impair(channel, fault, shield, self.arrays.matrix)
        self._pending: list[tuple[float, int, MergePlan]] = []  # (arrival, decision, plan)

    # ------------------------------------------------------------------ run
    def run(self, progress: Any = None) -> SimulationLog:
        """Warm up (compiled), then advance step by step to the end."""
        self.run_to(self.n_warmup)
        while not self.finished:
            if self.step_index >= self.stop_step:  # a stage ended on a Python step
                self.resume(layout.DONE)
                continue
            self._between_steps()
            if self._lost_due(self.t):  # a decision the compiled loop does not know of
                self.resume(layout.NEED_PYTHON)
            else:
                self.run_to(self.step_index + 1)
        return self.log

    def _between_steps(self) -> None:
        t = self.t
        if not self.channel_params.ideal:
            if (self.step_index - self.n_warmup) % self._broadcast_every == 0:
                self.channel.broadcast(t, self._state())
            self.channel.deliver(t)
            self._deliver_plans(t)
            self._degrade(t)
        self.fault.act(self, t)
        commanded = commanded_vehicles(self.arrays)
        self.shield.act(self, t, commanded)
        if commanded.size:
            self.commanded_at[self.step_index] = frozenset(commanded.tolist())

    def _state(self) -> dict[str, np.ndarray]:
        return {"x": self.x, "v": self.v, "a": self.a, "lane": self.lane,
                "active": self.active, "changing": self.origin != self.target}  # fmt: skip

    # ---------------------------------------------------------------- views
    def _view(self, t: float) -> Any:
        view = super()._view(t)
        return dataclasses.replace(view, fleet=self.nominal_fleet)

    def _identify_key_vehicles(self, ids: Any, changing: Any, t: float) -> None:
        before = len(self.key_groups)
        super()._identify_key_vehicles(ids, changing, t)
        if len(self.key_groups) > before:
            self.fault.on_entry(self, next(reversed(self.key_groups.values())), t)

    # ---------------------------------------------------------------- plans
    def _plan_new(self, ids: Any, changing: Any, t: float) -> None:
        """The engine's decisions (:meth:`Simulation._plan_new`) through the channel: the
        controller sees the channel's view, the plan is checked against that view and
        queued until it arrives."""
        assert self.controller is not None
        new = ids[(self.lane[ids] == Lane.RAMP) & ~changing & ~self.planned[ids]
                  & (self.x[ids] >= self.config.road.control_zone_start)]  # fmt: skip
        waiting = {p.group.vr for _, _, p in self._pending}
        due = [vr for vr in self._due(t) if vr not in waiting]
        for vr in [*new.tolist(), *due]:
            self.planned[vr] = True
            self._next_plan.pop(vr, None)
            true_view = self._view(t)
            group = find_key_vehicles(true_view, vr)
            seen = true_view if self.channel_params.ideal else self.channel.view(true_view)
            plan = self._decide(seen, group)
            plan = checked(plan, seen, group, name_of(self.controller))
            self.requests.append((seen, group))
            self.decisions.append(plan)
            self.log.meta.setdefault("plans", []).append(plan_record(plan))
            self.log.add_event(t, EventKind.PLAN, vr, other=group.vmc, x=self.x[vr],
                               value=int(plan.mode))  # fmt: skip
            if plan.fallback:
                self.log.add_event(t, EventKind.FALLBACK, vr, other=group.vmc, x=self.x[vr])
            delay = 0.0 if self.channel_params.ideal else self.channel.plan_delay()
            if math.isinf(delay):
                self.plans_lost += 1
                self._next_plan[vr] = t + self.config.control.replan_period
            elif delay == 0.0:
                self._execute(plan, len(self.decisions) - 1)
            else:
                self._pending.append((t + delay, len(self.decisions) - 1, plan))

    def _lost_due(self, t: float) -> list[int]:
        """Ramp vehicles whose last plan was lost and that are due for a new one."""
        return [vr for vr, when in self._next_plan.items() if when <= t + 1e-9
                and self.active[vr] and self.lane[vr] == Lane.RAMP
                and self.origin[vr] == self.target[vr]]  # fmt: skip

    def _due(self, t: float) -> list[int]:
        due = core.due_plans(self.core, t).tolist()
        return [*due, *(vr for vr in self._lost_due(t) if vr not in due)]

    def _deliver_plans(self, t: float) -> None:
        arrived = [(d, p) for when, d, p in self._pending if when <= t + 1e-9]
        self._pending = [item for item in self._pending if item[0] > t + 1e-9]
        for ident, plan in arrived:
            vr = plan.group.vr
            if (
                self.active[vr]
                and self.lane[vr] == Lane.RAMP
                and self.origin[vr] == self.target[vr]
            ):
                self._execute(plan, ident)

    def _execute(self, plan: MergePlan, ident: int) -> None:
        """Put ``plan`` into the engine's plan table (replacing its VR's live plan)."""
        vr = plan.group.vr
        ignores = self.fault.ignores(plan)
        row = encode_plan(
            plan,
            vr_commanded=bool(self.fleet.kind[vr] == Kind.CAV)
            and bool(np.isfinite(plan.merge_x))
            and vr not in ignores,
            vmc_commanded=plan.mode != Mode.NONE and plan.group.vmc not in ignores,
            vnr_commanded=plan.vv2 is not None and plan.group.vnr not in ignores,
            ident=ident,
        )
        c = self.arrays
        n = int(c.counters[layout.N_PLANS])
        c.counters[layout.N_PLANS] = add_plan(c.plan_int, c.plan_f, n, *row)
