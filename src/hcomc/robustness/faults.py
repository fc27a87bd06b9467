"""Injected faults (:class:`hcomc.robustness.settings.FaultParams`), acted out between steps.

A fault is timed from the moment the run's ramp vehicle enters the control zone (its key
vehicles are identified, before any control acts), with draws from the fault's own
generator derived from the run's seed: the same seed gives the same fault for every
controller, channel and shield setting, so their runs are paired.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.control.base import MergeGroup, MergePlan
from hcomc.road import Kind
from hcomc.robustness.settings import FaultParams

if TYPE_CHECKING:
    from hcomc.robustness.engine import FaultedSimulation

__all__ = ["FAULT_STREAM", "Fault"]

FAULT_STREAM = 0xFA17
"""Spawn key of a fault's generator: ``SeedSequence([seed, FAULT_STREAM])``."""


class Fault:
    """The fault of one run: what it does, to whom, and when."""

    def __init__(self, params: FaultParams, config: ScenarioConfig, seed: int) -> None:
        self.params = params
        rng = np.random.default_rng(np.random.SeedSequence([seed, FAULT_STREAM]))
        self.delay = float(rng.uniform(params.delay_min, params.delay_max))
        self.duration = float(rng.uniform(params.duration_min, params.duration_max))
        self.decel = params.decel or config.control.safety_emergency_decel
        self.vehicle = -1  # the vehicle the fault acts on, once known
        self.start = self.end = math.nan  # [s]
        self._braking = False
        self._ignoring: set[int] = set()

    @property
    def kind(self) -> str:
        """The fault's kind (``none`` for the nominal run)."""
        return self.params.kind

    def on_entry(self, sim: FaultedSimulation, group: MergeGroup, t: float) -> None:
        """The first ramp vehicle entered the control zone with key vehicles ``group``."""
        if self.vehicle >= 0 or self.kind == "none":
            return
        if self.kind in ("emergency_brake", "sensor_dropout"):
            who = int(getattr(group, self.params.role))
            if self.kind == "sensor_dropout" and (who < 0 or sim.fleet.kind[who] != Kind.CAV):
                return  # no CAV in that role: nothing to fail
            self.vehicle = who
            self.start, self.end = t + self.delay, t + self.delay + self.duration
        elif self.kind == "aggressive_hdv":
            keys = [int(i) for i in group.as_array() if i >= 0]
            hdvs = [i for i in keys if sim.fleet.kind[i] == Kind.HDV]
            driving = sim.driving
            driving.T[hdvs] = self.params.time_headway
            driving.s0[hdvs] = self.params.min_gap
            driving.a[hdvs] = self.params.max_accel
            self.vehicle, self.start = (hdvs[0] if hdvs else -1), t

    def act(self, sim: FaultedSimulation, t: float) -> None:
        """Start or end the emergency braking or the sensor dropout before the step at ``t``."""
        if self.kind not in ("emergency_brake", "sensor_dropout") or self.vehicle < 0:
            return
        on = self.start <= t + 1e-9 < self.end and bool(sim.active[self.vehicle])
        if on and not self._braking:
            held = -self.decel if self.kind == "emergency_brake" else float(sim.a[self.vehicle])
            sim.command(self.vehicle, held)
        elif self._braking and not on:
            sim.command(self.vehicle, math.nan)
        self._braking = on

    def drives(self, i: int) -> bool:
        """Whether the fault drives vehicle ``i`` now (the shield leaves it alone)."""
        return self._braking and i == self.vehicle

    def ignores(self, plan: MergePlan) -> set[int]:
        """Vehicles that ignore ``plan``: with ``ignore_command``, the first plan's
        cooperating vehicle (VR when it commands none), for the whole run."""
        if self.kind != "ignore_command":
            return set()
        if not self._ignoring:
            who = plan.cooperating if plan.cooperating >= 0 else plan.group.vr
            self._ignoring.add(int(who))
            self.vehicle, self.start = int(who), plan.t0
        return self._ignoring
