"""The read-only traffic view an engine hands to a merge controller."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.interface.fleet import Fleet
from hcomc.interface.plan import MergePlan
from hcomc.interface.ramp import Ramp
from hcomc.road import Kind

if TYPE_CHECKING:
    from hcomc.config import ScenarioConfig

_CAV = int(Kind.CAV)  # a plain int: an enum member's lookup costs more than the comparison


@dataclass(frozen=True, slots=True)
class TrafficView:
    """Read-only snapshot handed to a controller (arrays over all vehicle slots).

    Attributes
    ----------
    t : simulation time [s].
    x, v, a : (N,) front-bumper position [m], speed [m/s], acceleration [m/s^2].
    lane : (N,) current lane (:class:`hcomc.road.Lane`).
    active : (N,) vehicle is on the road.
    changing : (N,) vehicle is in a lane-change manoeuvre: between the start of its change
        and its arrival on the target lane's centre line (the engine: target lane differs
        from origin lane; SUMO co-simulation: off its origin lane or a change in progress).
        Its ``lane`` switches to the target at the lateral midpoint. Information for
        controllers; the key-vehicle rules go by ``lane`` alone.
    fleet : per-vehicle constants; config : the models' parameters (vehicles, lane changes,
        control).
    ramp : the on-ramp the decision is for (:class:`~hcomc.interface.ramp.Ramp`): its
        control zone, acceleration lane and lane codes, all a controller reads of the road.
    plans : the plans being executed.
    """

    t: float
    x: FloatArray
    v: FloatArray
    a: FloatArray
    lane: IntArray
    active: BoolArray
    changing: BoolArray
    fleet: Fleet
    config: ScenarioConfig
    ramp: Ramp
    plans: tuple[MergePlan, ...] = ()

    @classmethod
    def snapshot(
        cls,
        t: float,
        state: dict[str, np.ndarray],
        fleet: Fleet,
        config: ScenarioConfig,
        plans: tuple[MergePlan, ...] = (),
        ramp: Ramp | None = None,
    ) -> TrafficView:
        """A read-only view of an engine's state: copies of the ``x, v, a, lane, active,
        changing`` arrays, frozen, so a controller can never write the simulation state;
        ``ramp`` defaults to the paper's road of ``config`` (:meth:`Ramp.of
        <hcomc.interface.ramp.Ramp.of>`)."""

        def frozen(name: str) -> np.ndarray:
            out = np.array(state[name], copy=True)
            out.flags.writeable = False
            return out

        return cls(
            t=t, x=frozen("x"), v=frozen("v"), a=frozen("a"), lane=frozen("lane"),
            active=frozen("active"), changing=frozen("changing"), fleet=fleet, config=config,
            ramp=Ramp.of(config.road) if ramp is None else ramp, plans=plans,
        )  # fmt: skip

    def is_cav(self, i: int) -> bool:
        """Whether vehicle ``i`` exists (``i >= 0``; -1 is a missing key vehicle) and is a CAV."""
        return i >= 0 and bool(self.fleet.kind[i] == _CAV)

    def live_plan(self, vr: int) -> MergePlan | None:
        """The plan being executed for ramp vehicle ``vr``, if any."""
        return next((p for p in self.plans if p.group.vr == vr), None)
