"""A merge controller at every on-ramp of a corridor: local views, decisions, plan table.

Each on-ramp has its own controller, built from the corridor's ``[control]`` table with the
ramp's *local scenario* (:func:`ramp_config`): the paper's road (Section II-A) with this
ramp's geometry in corridor coordinates, the IDM of the corridor's mainline class for
HDVs and CAVs (CAVs without the constant-acceleration heuristic, coolness 0, as the
corridor engine drives them), the corridor's lane-change settings. The controller sees the
ramp's local view (ramp lane, mainline lanes 0 and 1 as ``RAMP``, ``MAIN_1``, ``MAIN_2``:
:func:`hcomc.sim.corridor.plans.fill_view`), with the ramp's geometry in corridor coordinates
as its :class:`~hcomc.interface.Ramp` (all a controller reads of the road), through the
same :class:`TrafficView` and :class:`~hcomc.interface.MergeGroup` as in the paper's scene,
and its plans are executed by the compiled step (:mod:`hcomc.sim.corridor.plans`). Plans of
different ramps, and of several VRs of one ramp, are live at the same time.

**One live plan per vehicle.** A plan may command a vehicle (its VMC, or VNR in lateral
mode) only if no live plan of another VR commands it; otherwise the new plan keeps its
mode and virtual vehicles for the record but does not command that vehicle, and the
conflict is counted for its VR. A VR's replan replaces its own live plan.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from hcomc.config import ScenarioConfig, load_config
from hcomc.control.key_group import find_key_vehicles
from hcomc.control.registry import make_controller
from hcomc.control.validation import checked, name_of, planned
from hcomc.corridor import Corridor, OnRamp
from hcomc.corridor.engine import ramp_road
from hcomc.interface import Fleet, MergeController, MergePlan, Mode, Ramp, TrafficView
from hcomc.rng import make_rng
from hcomc.road import Kind
from hcomc.sim.corridor.fleet import CorridorFleet
from hcomc.sim.corridor.layout import Layout
from hcomc.sim.corridor.plans import fill_view
from hcomc.sim.corridor.setup import ramp_code
from hcomc.sim.corridor.state import C_PENDING, C_PLANS, State, Vehicles
from hcomc.sim.step.plans import (
    P_ID,
    P_VMC,
    P_VMC_CMD,
    P_VNR,
    P_VNR_CMD,
    P_VR,
    add_plan,
    encode_plan,
)  # fmt: skip

__all__ = ["CorridorControl", "Decision", "ramp_config"]


def mainline_class(c: Corridor) -> str:
    """The vehicle class with the largest share of the mainline demand (the first class
    when there is no mainline demand)."""
    main = c.demand.get("main")
    if main is None or not main.classes:
        return next(iter(c.vehicles))
    return max(main.classes, key=lambda name: main.classes[name])


def ramp_config(c: Corridor, ramp: OnRamp) -> ScenarioConfig:
    """The local scenario of ``ramp`` its controller is built with (module docstring)."""
    vehicle = c.vehicles[mainline_class(c)]
    lc = c.lane_change
    duration = {"lane_change_duration": c.corridor.lane_change_duration}
    settings = {
        "name": f"{c.name}.{ramp.id}", "seed": c.corridor.seed, "dt": c.corridor.step_length,
        "duration": c.corridor.duration, "warmup": 0.0,
        "road": ramp_road(c, ramp, vehicle),
        "hdv": {**vehicle.idm(False), **duration},
        "cav": {**vehicle.idm(True), **duration, "coolness": 0.0},
        "lane_change": lc.model_dump(),
        "control": c.control.model_dump(),
    }  # fmt: skip
    return load_config("C1", **settings)


def view_fleet(c: Corridor, fleet: CorridorFleet, veh: Vehicles) -> Fleet:
    """The corridor's vehicles as the :class:`Fleet` controllers read (IDM for everyone:
    coolness 0, no improved IDM)."""
    n = fleet.depart.size
    widths = np.array([c.vehicles[name].width for name in fleet.classes])[fleet.vclass]
    matrix = np.vstack([veh.v0, veh.T, veh.s0, veh.a, veh.b, veh.delta, np.zeros(n)])
    return Fleet(
        kind=np.where(fleet.cav, int(Kind.CAV), int(Kind.HDV)).astype(np.int64),
        matrix=matrix,
        iidm=np.zeros(n, dtype=np.bool_),
        lc_duration=np.full(n, c.corridor.lane_change_duration),
        length=fleet.length,
        width=widths,
        scripted=np.zeros(n, dtype=np.bool_),
    )


@dataclass(frozen=True)
class Decision:
    """One controller decision: the plan, the ramp, and what it commands after the
    one-live-plan rule."""

    ramp: str
    plan: MergePlan
    vr_commanded: bool
    vmc_commanded: bool
    vnr_commanded: bool
    conflict: bool  # the plan wanted a vehicle another live plan commands


@dataclass
class CorridorControl:
    """The controllers of a corridor run and their decisions (module docstring)."""

    corridor: Corridor
    layout: Layout
    fleet: Fleet
    controllers: dict[int, tuple[str, ScenarioConfig, MergeController]]
    rng: np.random.Generator
    seed: int
    decisions: list[Decision] = field(default_factory=list)
    decision_seconds: float = 0.0

    @classmethod
    def build(cls, c: Corridor, layout: Layout, fleet: CorridorFleet, veh: Vehicles,
              seed: int) -> CorridorControl:  # fmt: skip
        """One controller per on-ramp, named by ``c.control.controller``."""
        controllers = {}
        for ramp in c.road.on_ramps:
            config = ramp_config(c, ramp)
            controller = make_controller(config)
            assert controller is not None, "CorridorControl needs a controller"
            controllers[ramp_code(layout, ramp.id, c)] = (ramp.id, config, controller)
        rng = make_rng(seed).spawn(1)[0]  # a stream of its own, beside the fleet's draws
        return cls(c, layout, view_fleet(c, fleet, veh), controllers, rng, seed)

    def view(self, s: State, t: float, ramp_code: int) -> TrafficView:
        """The controller's read-only view of ramp ``ramp_code`` at t."""
        fill_view(s, ramp_code, t)
        state = {"x": s.x, "v": s.v, "a": s.a, "lane": s.view_lane, "active": s.view_active,
                 "changing": s.target != s.code}  # fmt: skip
        n = int(s.counters[C_PLANS])
        plans = tuple(self.decisions[int(k)].plan for k in s.plan_int[:n, P_ID])
        config = self.controllers[ramp_code][1]
        ramp = Ramp.of(config.road)  # the ramp in corridor coordinates, the local lane codes
        return TrafficView.snapshot(t, state, self.fleet, config, plans, ramp)

    def decide(self, s: State, t: float) -> None:
        """Plan for every VR the step listed (``s.pending``), one after the other, each
        seeing the plans made before it."""
        started = time.perf_counter()
        for vr in s.pending[: int(s.counters[C_PENDING])].tolist():
            code = int(s.code[vr])
            ramp, _, controller = self.controllers[code]
            view = self.view(s, t, code)
            group = find_key_vehicles(view, vr)
            where = f"{self.corridor.name}, ramp {ramp}, seed {self.seed}"
            plan = planned(controller, view, group, self.rng.spawn(1)[0], where)
            self._enter(s, ramp, checked(plan, view, group, name_of(controller)))
        s.counters[C_PENDING] = 0
        self.decision_seconds += time.perf_counter() - started

    def _enter(self, s: State, ramp: str, plan: MergePlan) -> None:
        """Put ``plan`` in the plan table under the one-live-plan rule."""
        g = plan.group
        n = int(s.counters[C_PLANS])
        others = s.plan_int[:n][s.plan_int[:n, P_VR] != g.vr]
        taken = set(others[others[:, P_VMC_CMD] != 0, P_VMC].tolist())
        taken |= set(others[others[:, P_VNR_CMD] != 0, P_VNR].tolist())
        wants_vmc, wants_vnr = plan.mode != Mode.NONE, plan.vv2 is not None
        vmc_ok = wants_vmc and g.vmc not in taken
        vnr_ok = wants_vnr and g.vnr not in taken
        decision = Decision(
            ramp=ramp, plan=plan,
            vr_commanded=bool(self.fleet.kind[g.vr] == Kind.CAV and np.isfinite(plan.merge_x)),
            vmc_commanded=vmc_ok, vnr_commanded=vnr_ok,
            conflict=(wants_vmc and not vmc_ok) or (wants_vnr and not vnr_ok),
        )  # fmt: skip
        self.decisions.append(decision)
        row = encode_plan(plan, decision.vr_commanded, vmc_ok, vnr_ok, len(self.decisions) - 1)
        s.counters[C_PLANS] = add_plan(s.plan_int, s.plan_f, n, *row)

    def commanded_twice(self, s: State) -> list[int]:
        """Vehicles two live plans command now (the rule says: none)."""
        n = int(s.counters[C_PLANS])
        rows = s.plan_int[:n]
        ids = [*rows[rows[:, P_VMC_CMD] != 0, P_VMC].tolist(),
               *rows[rows[:, P_VNR_CMD] != 0, P_VNR].tolist()]  # fmt: skip
        return sorted({i for i in ids if ids.count(i) > 1})
