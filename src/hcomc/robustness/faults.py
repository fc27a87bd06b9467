"""Injected faults (:class:`hcomc.config.impairment_tables.FaultParams`), acted out between steps.

A fault is timed from the moment the run's ramp vehicle enters the control zone (its key
vehicles are identified, before any control acts), with draws from the fault's own
generator derived from the run's seed: the same seed gives the same fault for every
controller, channel and shield setting, so their runs are paired.

A faulty vehicle is driven from outside (:meth:`hcomc.sim.engine.Simulation.command`) during
its fault window: braking, holding an acceleration, or its car-following model evaluated on
what its faulty sensors (:func:`noisy_acceleration`) or its distracted driver
(:func:`distracted_acceleration`) perceive, computed between two steps.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.config.impairment_tables import FaultParams
from hcomc.equations.car_following import follow_accel
from hcomc.interface import MergeGroup, MergePlan
from hcomc.interface.listener import ListenedRun
from hcomc.road import Kind
from hcomc.robustness.run_state import broadcast_state

__all__ = [
    "FAULT_STREAM",
    "Fault",
    "Faults",
    "History",
    "distracted_acceleration",
    "noisy_acceleration",
]

FAULT_STREAM = 0xFA17
"""Spawn key of a fault's generator: ``SeedSequence([seed, FAULT_STREAM])`` for the first
fault of a run, ``SeedSequence([seed, FAULT_STREAM, k])`` for its k-th (k >= 1)."""


MIN_SEEN_GAP = 0.1
"""[m] A perceived gap is kept at least this long: a sensor or a driver never sees an overlap
with its leader (a true overlap is a collision, logged by the engine)."""

WINDOWED = ("emergency_brake", "sensor_dropout", "sensor_noise", "distracted_hdv")
"""Faults that act during a seeded window after the ramp vehicle's entry."""


class History:
    """The last ``size`` states (x, v, a, lane, active) of every vehicle, newest last."""

    def __init__(self, size: int) -> None:
        self.size = max(1, size)
        self.states: list[dict[str, np.ndarray]] = []

    def push(self, sim: ListenedRun) -> None:
        """Store the state before the next step."""
        self.states.append({"x": sim.x.copy(), "v": sim.v.copy(), "a": sim.a.copy(),
                            "lane": sim.lane.copy(), "active": sim.active.copy()})  # fmt: skip
        if len(self.states) > self.size:
            del self.states[0]

    @property
    def oldest(self) -> dict[str, np.ndarray]:
        """The state ``size - 1`` steps ago (the oldest kept, while fewer were pushed)."""
        return self.states[0]


def _leader_in(state: dict[str, np.ndarray], i: int, lane: int) -> int:
    """The nearest vehicle ahead of ``i`` in ``lane`` in ``state`` (-1: none)."""
    x, there = state["x"], np.flatnonzero(state["active"] & (state["lane"] == lane))
    ahead = there[(x[there] > x[i]) & (there != i)]
    return int(ahead[np.argmin(x[ahead])]) if ahead.size else -1


def _follow(sim: ListenedRun, i: int, s: float, v: float, vl: float, al: float) -> float:
    """Vehicle ``i``'s car-following acceleration (Eq. 1, or Eq. 3 for a CAV) with the
    parameters it drives with, on a perceived gap ``s`` and speeds ``v``, ``vl``."""
    d = sim.driving
    return float(follow_accel(s, v, vl, al, d.v0[i], d.T[i], d.s0[i], d.a[i], d.b[i],
                              d.delta[i], d.coolness[i], bool(d.iidm[i])))  # fmt: skip


def noisy_acceleration(
    sim: ListenedRun, i: int, gap_noise: float, speed_noise: float, rng: np.random.Generator
) -> float:
    """Vehicle ``i``'s acceleration on its faulty sensors: its car following behind the true
    leader in its lane, with the gap and the leader's speed measured with Gaussian errors of
    standard deviations ``gap_noise`` [m] and ``speed_noise`` [m/s] (the measured gap at least
    :data:`MIN_SEEN_GAP`; the leader's acceleration exact, as broadcast)."""
    j = _leader_in(broadcast_state(sim), i, int(sim.lane[i]))
    e_gap, e_speed = rng.standard_normal(2)
    if j < 0:
        return _follow(sim, i, math.inf, float(sim.v[i]), float(sim.v[i]), 0.0)
    gap = float(sim.x[j] - sim.fleet.length[j] - sim.x[i]) + gap_noise * e_gap
    vl = max(0.0, float(sim.v[j]) + speed_noise * e_speed)
    return _follow(sim, i, max(gap, MIN_SEEN_GAP), float(sim.v[i]), vl, float(sim.a[j]))


def distracted_acceleration(
    sim: ListenedRun, i: int, seen: dict[str, np.ndarray], gap_error: float
) -> float:
    """Vehicle ``i``'s acceleration when its driver acts on the older state ``seen``: the
    leader it saw in its lane then, gap and speeds as they were, the gap scaled by
    ``exp(gap_error)`` (``gap_error`` = V_s w, Eq. 2's relative estimation error)."""
    j = _leader_in(seen, i, int(sim.lane[i]))
    v = float(seen["v"][i])
    if j < 0:
        return _follow(sim, i, math.inf, v, v, 0.0)
    gap = float(seen["x"][j] - sim.fleet.length[j] - seen["x"][i]) * math.exp(gap_error)
    return _follow(sim, i, max(gap, MIN_SEEN_GAP), v, float(seen["v"][j]), float(seen["a"][j]))


class Fault:
    """The fault of one run: what it does, to whom, and when."""

    def __init__(
        self, params: FaultParams, config: ScenarioConfig, seed: int, index: int = 0
    ) -> None:
        self.params = params
        key = [seed, FAULT_STREAM] + ([index] if index else [])
        self.rng = np.random.default_rng(np.random.SeedSequence(key))
        self.delay = float(self.rng.uniform(params.delay_min, params.delay_max))
        self.duration = float(self.rng.uniform(params.duration_min, params.duration_max))
        self.decel = params.decel or config.control.safety_emergency_decel
        self.vehicles: list[int] = []  # the vehicles the fault acts on, once known
        self.start = self.end = math.nan  # [s]
        self._on = False
        self._ignoring: set[int] = set()
        self._held: dict[int, float] = {}
        hdv = config.hdv
        self.history = History(round(params.distracted_delay / config.dt) + 1)
        self._ou = (math.exp(-config.dt / hdv.error_correlation_time),
                    math.sqrt(2.0 * config.dt / hdv.error_correlation_time))  # fmt: skip
        self._w: dict[int, float] = {}  # distracted drivers' gap-error processes

    @property
    def kind(self) -> str:
        """The fault's kind (``none`` for the nominal run)."""
        return self.params.kind

    @property
    def vehicle(self) -> int:
        """The (first) vehicle the fault acts on, -1 while none."""
        return self.vehicles[0] if self.vehicles else -1

    def on_entry(self, sim: ListenedRun, group: MergeGroup, t: float) -> None:
        """The first ramp vehicle entered the control zone with key vehicles ``group``."""
        if self.vehicles or self.kind in ("none", "ignore_command", "stalled_vehicle"):
            return
        keys = [int(i) for i in group.as_array() if i >= 0]
        if self.kind in ("aggressive_hdv", "distracted_hdv"):
            self.vehicles = [i for i in keys if sim.fleet.kind[i] == Kind.HDV]
        else:
            who = int(getattr(group, self.params.role))
            cav_only = self.kind in ("sensor_dropout", "sensor_noise")
            if who >= 0 and not (cav_only and sim.fleet.kind[who] != Kind.CAV):
                self.vehicles = [who]
        if self.kind == "aggressive_hdv":
            driving, hdvs = sim.driving, self.vehicles
            driving.T[hdvs] = self.params.time_headway
            driving.s0[hdvs] = self.params.min_gap
            driving.a[hdvs] = self.params.max_accel
            self.start = t
        elif self.vehicles:
            self.start, self.end = t + self.delay, t + self.delay + self.duration
        if self.kind == "distracted_hdv":  # w(0) ~ N(0, 1), as Eq. 2's errors
            self._w = {i: float(self.rng.standard_normal()) for i in self.vehicles}

    def act(self, sim: ListenedRun, t: float) -> None:
        """Drive the faulty vehicles for the step at ``t`` during the fault window, and hand
        them back to their model when it ends."""
        if self.kind == "distracted_hdv":
            self.history.push(sim)
        if self.kind not in WINDOWED or not self.vehicles:
            return
        on = self.start <= t + 1e-9 < self.end
        for i in self.vehicles:
            if on and sim.active[i]:
                sim.command(i, self._acceleration(sim, i))
            elif self._on:
                sim.command(i, math.nan)
        self._on = on

    def _acceleration(self, sim: ListenedRun, i: int) -> float:
        p = self.params
        if self.kind == "emergency_brake":
            return -self.decel
        if self.kind == "sensor_dropout":
            return self._held.setdefault(i, float(sim.a[i]))
        if self.kind == "sensor_noise":
            return noisy_acceleration(sim, i, p.gap_noise, p.speed_noise, self.rng)
        decay, kick = self._ou
        self._w[i] = decay * self._w[i] + kick * float(self.rng.standard_normal())
        seen = self.history.oldest
        return distracted_acceleration(sim, i, seen, p.distracted_gap_error * self._w[i])

    def drives(self, i: int) -> bool:
        """Whether the fault drives vehicle ``i`` now (the shield leaves it alone)."""
        return self._on and i in self.vehicles

    def ignores(self, plan: MergePlan) -> set[int]:
        """Vehicles that ignore ``plan``: with ``ignore_command``, the first plan's
        cooperating vehicle (VR when it commands none), for the whole run."""
        if self.kind != "ignore_command":
            return set()
        if not self._ignoring:
            who = plan.cooperating if plan.cooperating >= 0 else plan.group.vr
            self._ignoring.add(int(who))
            self.vehicles, self.start = [int(who)], plan.t0
        return self._ignoring


class Faults:
    """The faults of one run (a config's ``[[faults]]``), each with its own seeded timing,
    acted out in their listed order (where two drive one vehicle in the same step, the
    later one's command stands). No fault: one nominal entry."""

    def __init__(self, params: Sequence[FaultParams], config: ScenarioConfig, seed: int) -> None:
        self.each = [Fault(p, config, seed, k) for k, p in enumerate(params or [FaultParams()])]

    @property
    def first(self) -> Fault:
        """The first fault (the nominal one when the run has none)."""
        return self.each[0]

    def stand(self, stalled: Sequence[int], t: float) -> None:
        """The ``stalled_vehicle`` faults, in their order, are the run's stalled vehicles
        ``stalled`` (:mod:`hcomc.sim.stalled`), standing from ``t``."""
        mine = [fault for fault in self.each if fault.kind == "stalled_vehicle"]
        for fault, i in zip(mine, stalled, strict=True):
            fault.vehicles, fault.start = [int(i)], t

    def on_entry(self, sim: ListenedRun, group: MergeGroup, t: float) -> None:
        """The first ramp vehicle entered the control zone with key vehicles ``group``."""
        for fault in self.each:
            fault.on_entry(sim, group, t)

    def act(self, sim: ListenedRun, t: float) -> None:
        """Every fault's step at ``t``."""
        for fault in self.each:
            fault.act(sim, t)

    def drives(self, i: int) -> bool:
        """Whether a fault drives vehicle ``i`` now (the shield leaves it alone)."""
        return any(fault.drives(i) for fault in self.each)

    def ignores(self, plan: MergePlan) -> set[int]:
        """Vehicles that ignore ``plan`` by any fault."""
        return set().union(*(fault.ignores(plan) for fault in self.each))
