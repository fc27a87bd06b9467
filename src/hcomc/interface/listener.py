"""Step listeners: code that acts on a run between its steps, on either engine.

A listener is handed to an engine when the run is made (``Simulation(config, seed,
listeners=[...])``, ``SumoSimulation(...)`` alike) and is called at fixed points of every
step, the way SUMO calls a ``traci.StepListener``: before each step from the end of the
warm-up on, when a ramp vehicle's key vehicles are found, and around each of the
controller's decisions (what the controller sees, when its plan reaches the vehicles, which
vehicles follow it). Between two steps it may drive a vehicle from outside
(:meth:`ListenedRun.command`), change the parameters the engine drives a vehicle with
(:attr:`ListenedRun.driving`), put a plan into force later (:meth:`ListenedRun.execute`),
and hold or release a commanded merge. It sees the run only through :class:`ListenedRun`, so
one listener works on any engine that implements it.

The robustness layer's V2X channel, faults and safety shield are one
(:class:`hcomc.robustness.impairments.Impairments`). A run with listeners that do nothing is
the run without them, bit for bit (the engine contract checks it).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import ScenarioConfig
from hcomc.interface.fleet import Fleet
from hcomc.interface.plan import MergeGroup, MergePlan
from hcomc.interface.ramp import Ramp
from hcomc.interface.view import TrafficView

__all__ = ["ListenedRun", "StepListener"]


class ListenedRun(Protocol):
    """A run as its listeners see it between two steps: the true state of every vehicle
    (indexed by vehicle, ``active`` on the road), the fleet the controllers know and the
    parameters the engine drives with, and the ways to act on the run."""

    config: ScenarioConfig
    seed: int
    dt: float
    n_warmup: int
    fleet: Fleet  # the nominal parameters (what controllers predict with)
    decisions: list[MergePlan]
    ramps: tuple[Ramp, ...]  # the road's on-ramps (lane-code order), as controllers see them
    stalled: IntArray  # the stalled vehicles of its [[faults]], in their order

    @property
    def key_groups(self) -> dict[int, MergeGroup]:
        """Key vehicles of each ramp vehicle, found when it entered the control zone."""
        ...

    @property
    def t(self) -> float:
        """The time of the step about to be taken [s] (0 at the end of the warm-up)."""
        ...

    @property
    def step_index(self) -> int:
        """Steps taken, warm-up included."""
        ...

    @property
    def x(self) -> FloatArray:
        """(N,) front-bumper position [m]."""
        ...

    @property
    def v(self) -> FloatArray:
        """(N,) speed [m/s]."""
        ...

    @property
    def a(self) -> FloatArray:
        """(N,) acceleration [m/s^2]."""
        ...

    @property
    def lane(self) -> IntArray:
        """(N,) the lane the vehicle's centre is in (:class:`hcomc.road.Lane`)."""
        ...

    @property
    def origin(self) -> IntArray:
        """(N,) the lane a lane change in progress started from (else ``lane``)."""
        ...

    @property
    def target(self) -> IntArray:
        """(N,) the lane a lane change in progress goes to (else ``lane``)."""
        ...

    @property
    def active(self) -> BoolArray:
        """(N,) on the road."""
        ...

    @property
    def driving(self) -> Fleet:
        """The parameters the engine drives each vehicle with; a listener may change them
        (an aggressive driver, a degraded headway) while ``fleet`` stays nominal."""
        ...

    def command(self, i: int, accel: float, /) -> None:
        """Drive vehicle ``i`` at ``accel`` [m/s^2] from the next step on (limited to the
        emergency deceleration and v >= 0, no lane change of its own); NaN hands it back."""
        ...

    def follow(self, ids: IntArray, leader: IntArray, /) -> FloatArray:
        """The car-following acceleration (Eq. 1-3) of vehicles ``ids`` behind ``leader``."""
        ...

    def execute(self, plan: MergePlan, ident: int, /) -> None:
        """Put decision ``ident``'s ``plan`` into force now (replacing its VR's live plan)."""
        ...

    def may_execute(self, vr: int, /) -> bool:
        """Whether ramp vehicle ``vr`` can still act on a plan (on the ramp, not changing)."""
        ...

    def commanded(self) -> IntArray:
        """Vehicles a live plan commands now: VR until its plan releases it (its commanded
        change included), a commanded cooperating vehicle (VMC) and a commanded VNR."""
        ...

    def merges_due(self) -> IntArray:
        """Ramp vehicles whose commanded merge may start in the next step."""
        ...

    def hold_merge(self, vr: int, /) -> None:
        """Keep VR's commanded merge from starting in the next step."""
        ...

    def release_merge(self, vr: int, /) -> None:
        """Hand VR back to merging by gap acceptance (its plan no longer commands it)."""
        ...

    def note(self, kind: int, vehicle: int, other: int = -1, value: float = 0.0, /) -> None:
        """Record an event of ``kind`` (:class:`hcomc.sim.log.EventKind`) at the current time
        in the run's log (what a listener did, for the metrics and the replay)."""
        ...


class StepListener:
    """A listener whose every hook does nothing; subclass it and override the hooks you
    need. ``run`` is the :class:`ListenedRun` the listener was given to."""

    def attach(self, run: ListenedRun) -> None:
        """Called once, when the engine is made with this listener (before its first step)."""

    def before_step(self, run: ListenedRun, t: float) -> None:
        """Called before each step from the end of the warm-up on; ``t`` is ``run.t``."""

    def on_key_vehicles(self, run: ListenedRun, group: MergeGroup, t: float) -> None:
        """A ramp vehicle entered the control zone and its key vehicles ``group`` were found."""

    def decisions_due(self, run: ListenedRun, t: float) -> Sequence[int]:
        """Ramp vehicles the listener wants a decision for at ``t`` (besides the engine's)."""
        return ()

    def holds(self, vr: int) -> bool:
        """Whether no decision is to be made for ``vr`` now (its last plan is on its way)."""
        return False

    def view(self, run: ListenedRun, view: TrafficView) -> TrafficView:
        """What the controller sees instead of the true state ``view``."""
        return view

    def send(self, run: ListenedRun, plan: MergePlan, ident: int, t: float) -> bool:
        """Decision ``ident``'s plan leaves the controller at ``t``: True puts it into force
        now; False means the listener took it (it calls ``run.execute`` when it arrives, or
        never)."""
        return True

    def ignores(self, plan: MergePlan) -> frozenset[int]:
        """Vehicles that will not follow ``plan``'s commands."""
        return frozenset()
