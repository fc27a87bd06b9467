"""What a run drives on and who drives on it: the road's lane table, the demand and the
fleet, drawn for one run.

:class:`hcomc.sim.engine.Simulation` takes them from a *scene maker*, a function of the
scenario and the run's generator (:data:`SceneMaker`). The paper's scenarios have one,
:func:`paper_scene`: the paper's road (:func:`hcomc.sim.roads.paper_lanes`), the
demand of the scenario's ``[demand]`` table and the fleet of its ``[hdv]`` and ``[cav]``
tables. Another road is another scene maker: the same engine drives any lane table.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.interface import Fleet
from hcomc.sim.demand import Demand, generate_demand
from hcomc.sim.lane_table import KIND_OFF, LaneTable
from hcomc.sim.roads import paper_lanes

__all__ = ["Scene", "SceneMaker", "paper_scene"]


@dataclass(frozen=True, slots=True)
class Scene:
    """One run's road (its lane table), every vehicle it releases (sorted by release
    time; their lanes and routes are codes of ``lanes``) and their parameters.

    A vehicle waits in the release queue of its demand lane; ``release_last`` (L,) gives,
    for each lane's queue, the last lane code its vehicles may enter by (the one with the
    most free road ahead, as SUMO's ``departLane="best"``; a corridor's mainline origin
    spans its lanes); by default each queue releases into its own lane only. ``classes``
    names the vehicle classes of a road with several (a corridor's cars and trucks) and
    ``vclass`` (N,) each vehicle's index into it; the engine does not read them (the fleet
    holds every vehicle's parameters), the measurements of a run do."""

    lanes: LaneTable
    demand: Demand
    fleet: Fleet
    release_last: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    classes: tuple[str, ...] = ()
    vclass: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.int64))

    def __post_init__(self) -> None:
        n_lanes = self.lanes.n_lanes
        if self.release_last.size == 0:
            object.__setattr__(self, "release_last", np.arange(n_lanes, dtype=np.int64))
        if self.release_last.shape != (n_lanes,) or (self.release_last < np.arange(n_lanes)).any():
            raise ValueError(f"release_last {self.release_last.tolist()}: one code per lane, "
                             "at least the lane's own")  # fmt: skip
        lane, route = self.demand.lane, self.demand.route
        if lane.size and (lane.min() < 0 or lane.max() >= n_lanes):
            raise ValueError(f"demand lanes {sorted(set(lane.tolist()))}: the road's lane "
                             f"codes are 0 to {n_lanes - 1}")  # fmt: skip
        if self.classes and (self.vclass.shape != lane.shape or self.vclass.max(initial=0)
                             >= len(self.classes)):  # fmt: skip
            raise ValueError(f"vclass: one index into classes {list(self.classes)} per vehicle")
        exits = set(self.lanes.codes_of_kind(KIND_OFF).tolist()) | {-1}
        if not set(route.tolist()) <= exits:
            wrong = sorted(set(route.tolist()) - exits)
            raise ValueError(f"demand routes {wrong}: allowed: {sorted(exits)} (an off-ramp "
                             "lane's code, -1: the mainline's end)")  # fmt: skip


SceneMaker = Callable[[ScenarioConfig, np.random.Generator], Scene]
"""A function that draws a run's :class:`Scene` from its scenario with the run's generator
(the generator's draws after it are the run's own: perception errors, controllers)."""


def paper_scene(config: ScenarioConfig, rng: np.random.Generator) -> Scene:
    """The paper's road with the demand and fleet of ``config`` (module docstring)."""
    demand = generate_demand(config, rng)
    fleet = Fleet.build(config, demand.kind, demand.scripted)
    return Scene(paper_lanes(config.road), demand, fleet)
