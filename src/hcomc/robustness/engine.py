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
from typing import Any

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.interface import MergeController, MergePlan, Mode
from hcomc.road import Kind, Lane
from hcomc.robustness.impairments import Impairments
from hcomc.robustness.settings import ChannelParams, FaultParams, ShieldParams
from hcomc.robustness.shield import commanded_vehicles
from hcomc.sim.engine import Simulation
from hcomc.sim.log import SimulationLog
from hcomc.sim.step import loop as step_loop
from hcomc.sim.step import state as layout
from hcomc.sim.step.plans import add_plan, encode_plan

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
        self._channel_step(t)
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
        self._tell_fault_of_entry(before, t)

    # ---------------------------------------------------------------- plans
    def _plan_new(self, ids: Any, changing: Any, t: float) -> None:
        """The engine's decisions (:meth:`Simulation._plan_new`) through the channel: the
        controller sees the channel's view, the plan is checked against that view and
        queued until it arrives."""
        assert self.controller is not None
        new = ids[(self.lane[ids] == Lane.RAMP) & ~changing & ~self.planned[ids]
                  & (self.x[ids] >= self.config.road.control_zone_start)]  # fmt: skip
        waiting = self._waiting()
        due = [vr for vr in self._due(t) if vr not in waiting]
        for vr in [*new.tolist(), *due]:
            self._decision(vr, t)

    def _may_execute(self, vr: int) -> bool:
        """Whether ramp vehicle ``vr`` is on the road, on the ramp and not changing lanes."""
        return bool(self.active[vr] and self.lane[vr] == Lane.RAMP
                    and self.origin[vr] == self.target[vr])  # fmt: skip

    def _due(self, t: float) -> list[int]:
        due = step_loop.due_plans(self.core, t).tolist()
        return [*due, *(vr for vr in self._lost_due(t) if vr not in due)]

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
