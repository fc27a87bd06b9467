"""The engine protocol: what a simulator running merge controllers offers to the layers above.

Both our engine (:class:`hcomc.sim.engine.Simulation`) and the SUMO co-simulation
(:class:`hcomc.sumo.cosim.SumoSimulation`) implement it, so experiments, metrics and reports
run on either; :func:`hcomc.sim.contract.check_engine` checks an implementation (the test
suite runs it on both). ``LogT_co`` is the type of the run's log (both engines write a
:class:`hcomc.sim.log.SimulationLog`; the protocol lives below the engine and does not name it).

Step listeners (:mod:`hcomc.interface.listener`) are given to an engine when it is made
(``listeners=[...]``) and act on its run between steps; the robustness layer's V2X channel,
faults and shield are one.

Batching is a capability, not a kind of engine: a class that can run many runs of its own
as one batch defines the class method ``run_together(engines, threads=None)`` itself (not
inherited: a subclass that changes how a run advances must not be batched by its parent's
method), and :func:`run_all` uses it for that class's runs and runs every other one alone.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol, TypeVar

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.interface.controller import MergeController
from hcomc.interface.fleet import Fleet
from hcomc.interface.listener import StepListener
from hcomc.interface.plan import MergeGroup, MergePlan
from hcomc.interface.view import TrafficView

LogT_co = TypeVar("LogT_co", covariant=True)


class Engine(Protocol[LogT_co]):
    """One run of a scenario with one seed, driving a merge controller.

    The state arrays are indexed by vehicle (demand order), with every vehicle of the run
    allocated from the start (``active`` says which are on the road).
    """

    @property
    def config(self) -> ScenarioConfig:
        """The scenario."""

    @property
    def seed(self) -> int:
        """The run's seed (all randomness derives from it)."""

    @property
    def fleet(self) -> Fleet:
        """Per-vehicle constants (Eq. 1-3 parameters, kind, size)."""

    @property
    def controller(self) -> MergeController | None:
        """The merge controller (None: no cooperative control)."""

    @property
    def n_warmup(self) -> int:
        """Steps of the warm-up (before t = 0, not logged)."""

    @property
    def n_steps(self) -> int:
        """Steps after the warm-up (the scenario's duration)."""

    @property
    def t(self) -> float:
        """Current simulation time [s] (0 at the end of the warm-up)."""

    @property
    def x(self) -> np.ndarray:
        """(N,) front-bumper position [m]."""

    @property
    def v(self) -> np.ndarray:
        """(N,) speed [m/s]."""

    @property
    def lane(self) -> np.ndarray:
        """(N,) lane (:class:`hcomc.road.Lane`)."""

    @property
    def active(self) -> np.ndarray:
        """(N,) on the road."""

    @property
    def key_groups(self) -> dict[int, MergeGroup]:
        """Key vehicles of each ramp vehicle, found when it entered the control zone."""

    @property
    def key_group(self) -> MergeGroup | None:
        """Key vehicles of the first ramp vehicle that entered the control zone."""

    @property
    def decisions(self) -> list[MergePlan]:
        """Every plan the controller returned, in order."""

    @property
    def requests(self) -> list[tuple[TrafficView, MergeGroup]]:
        """What each decision was asked: the view and key vehicles, in the order of
        ``decisions``."""

    @property
    def listeners(self) -> Sequence[StepListener]:
        """The step listeners the engine was made with
        (:mod:`hcomc.interface.listener`)."""

    @property
    def log(self) -> LogT_co:
        """The run's log (complete after :meth:`run`)."""

    def step(self) -> None:
        """Advance the run by one time step."""

    def run(self, progress: Callable[[int, int], None] | None = None) -> LogT_co:
        """Warm up, simulate the scenario's duration and return the log."""


def run_all(engines: Sequence[Engine[Any]], *, threads: int | None = None) -> None:
    """Run every engine of ``engines`` to its end: the runs of a class that defines
    ``run_together`` as one batch per class (on ``threads`` cores), every other run alone,
    classes in order of first appearance. The logs are each engine's ``log``."""
    groups: dict[type, list[Engine[Any]]] = {}
    for engine in engines:
        groups.setdefault(type(engine), []).append(engine)
    for kind, group in groups.items():
        own = "run_together" in vars(kind)  # defined by the class itself, not inherited
        together = getattr(kind, "run_together", None) if own else None
        if together is not None:
            together(group, threads=threads)
        else:
            for engine in group:
                engine.run()
