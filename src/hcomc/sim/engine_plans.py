"""The engine's live plans as its step listeners and decisions reach them.

:class:`EnginePlans` is the part of :class:`hcomc.sim.engine.Simulation` that reads and
writes the plan table of the compiled state (:mod:`hcomc.sim.step.plans`, one row per live
plan), so that nothing outside the engine does: putting a decision into force
(:meth:`~hcomc.sim.engine_plans.EnginePlans.execute`), the commanded vehicles, and holding
or releasing a commanded merge (the safety shield's levers). The SUMO co-simulation offers
the same methods on its list of plans (:class:`hcomc.sumo.cosim.SumoSimulation`).
"""

from __future__ import annotations

import numpy as np

from hcomc._typing import IntArray
from hcomc.interface import MergePlan, Mode
from hcomc.road import Kind
from hcomc.sim.engine_setup import EngineSetup
from hcomc.sim.lane_table import KIND_MAIN, L_KIND
from hcomc.sim.plan_execution import ActivePlan, plan_views
from hcomc.sim.step import plans as table
from hcomc.sim.step import state as layout
from hcomc.sim.step.plans import add_plan, encode_plan

__all__ = ["EnginePlans"]


class EnginePlans(EngineSetup):
    """Live plans of a run of our engine, in its plan table."""

    @property
    def plans(self) -> list[ActivePlan]:
        """The plans being executed, in the order they were made, with their progress (a
        copy: the run executes them from the plan table of its compiled state)."""
        c = self.arrays
        return plan_views(c.plan_int, int(c.counters[layout.N_PLANS]), self.decisions)

    def _live(self) -> tuple[np.ndarray, np.ndarray]:
        """The plan table's live rows (integer and float columns; views)."""
        n = int(self.arrays.counters[layout.N_PLANS])
        return self.arrays.plan_int[:n], self.arrays.plan_f[:n]

    def execute(self, plan: MergePlan, ident: int) -> None:
        """Put decision ``ident``'s ``plan`` into force: a row of the plan table, replacing its
        VR's live plan, commanding the CAVs it names but those a listener says ignore it."""
        ignores = frozenset().union(*(listener.ignores(plan) for listener in self.listeners))
        vr = plan.group.vr
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

    def may_execute(self, vr: int) -> bool:
        """Whether ramp vehicle ``vr`` is on the road, in its ramp lane and not changing
        lanes."""
        on_ramp = self.arrays.road_int[L_KIND, self.lane[vr]] != KIND_MAIN
        return bool(self.active[vr] and on_ramp and self.origin[vr] == self.target[vr])

    def commanded(self) -> IntArray:
        """Vehicles a live plan commands now: VR until its plan releases it (on the ramp and in
        its commanded change), a commanded cooperating vehicle (VMC) and a commanded VNR."""
        pi, _ = self._live()
        vr = pi[(pi[:, table.P_VR_CMD] != 0) & (pi[:, table.P_RELEASED] == 0), table.P_VR]
        vmc = pi[pi[:, table.P_VMC_CMD] != 0, table.P_VMC]
        vnr = pi[pi[:, table.P_VNR_CMD] != 0, table.P_VNR]
        ids = np.concatenate([vr, vmc, vnr])
        return np.unique(ids[ids >= 0])

    def merges_due(self) -> IntArray:
        """Ramp vehicles whose commanded merge may start in the next step: commanded, not
        started nor released, on the ramp, not changing lanes, at or past the merge position."""
        pi, pf = self._live()
        vr = pi[:, table.P_VR]
        waiting = ((pi[:, table.P_VR_CMD] != 0) & (pi[:, table.P_VR_STARTED] == 0)
                   & (pi[:, table.P_RELEASED] == 0) & (self.origin[vr] == self.target[vr])
                   & (self.arrays.road_int[L_KIND, self.lane[vr]] != KIND_MAIN)
                   & (self.x[vr] >= pf[:, table.F_MERGE_X]))  # fmt: skip
        return vr[waiting]

    def note(self, kind: int, vehicle: int, other: int = -1, value: float = 0.0) -> None:
        """Record a listener's event of ``kind`` now, at the vehicle's position."""
        self.log.add_event(self.t, kind, vehicle, other=other, x=self.x[vehicle], value=value)

    def hold_merge(self, vr: int) -> None:
        """Move VR's merge position just past where it will be after the next step."""
        pi, pf = self._live()
        pf[pi[:, table.P_VR] == vr, table.F_MERGE_X] = self.x[vr] + self.v[vr] * self.dt + 1e-6

    def release_merge(self, vr: int) -> None:
        """Release VR from its plan to gap acceptance."""
        pi, _ = self._live()
        pi[pi[:, table.P_VR] == vr, table.P_RELEASED] = 1
