"""The compilation stages of the simulation engines (:class:`hcomc._compiling.Stage`).

Each stage's workload is a short real run, so that it compiles exactly the kernels that runs
of its kind use; :func:`hcomc._compiling.ensure` runs the missing ones before a command or an
environment simulates. The cold seconds are those of ``benchmarks/compile_profile.py`` on the
development machine (Intel Xeon, one core).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from functools import partial

from hcomc._compiling import Stage, cache_directory, ensure


def scenario_runs(*controls: tuple[str, str]) -> None:
    """Short runs of Condition 2 (merge near t = 35 s), one per (controller, optimiser)."""
    from hcomc.config import load_config
    from hcomc.sim.engine import Simulation

    for controller, optimizer in controls:
        control = {"controller": controller, "optimizer": optimizer}
        Simulation(load_config("C2", duration=40.0, control=control), 0).run()


def lane_change_drawing() -> None:
    """The replay's drawing of lane changes (Eq. 4)."""
    import numpy as np

    from hcomc.equations.lane_change import lateral_offset

    lateral_offset(np.linspace(0.0, 100.0, 3), 0.0, 100.0, 0.0, 3.75)


def corridor_runs() -> None:
    """A short run of the corridor preset, uncontrolled and with HCOMC at every ramp."""
    from hcomc.corridor.loading import load_corridor
    from hcomc.sim.corridor_scene import corridor_config, corridor_scene
    from hcomc.sim.engine import Simulation

    corridor = load_corridor("corridor", {"corridor.duration": 30.0})
    for controller in ("none", "hcomc"):
        config = corridor_config(corridor, control={"controller": controller})
        Simulation(config, 0, scene=corridor_scene(corridor)).run()


STAGES: dict[str, Stage] = {
    "step": Stage("simulation step", partial(scenario_runs, ("none", "nsga2")), 65.0),
    "prediction": Stage(
        "merge prediction of FIFO, Game and HCOMC",
        partial(scenario_runs, ("fifo", "nsga2"), ("game", "nsga2")),
        337.0,
    ),
    "nsga2": Stage("NSGA-II", partial(scenario_runs, ("hcomc", "nsga2")), 14.0),
    "pso-sa": Stage("PSO, SA", partial(scenario_runs, ("hcomc", "pso"), ("hcomc", "sa")), 5.0),
    "replay": Stage("replay", lane_change_drawing, 1.0),
    "corridor": Stage("corridor runs", corridor_runs, 60.0),
}
"""The engines' stages by key (the scenario engine's four, the replay's, the corridor's)."""

SCENARIO = ("step", "prediction", "nsga2", "pso-sa")
"""What a run of the paper's scenarios with any controller and optimiser compiles."""


def _say(text: str, end: str = "\n") -> None:
    print(text, end=end, file=sys.stderr, flush=True)


def ensure_kernels(keys: Sequence[str]) -> None:
    """Compile the stages ``keys`` in this process if they are not cached, with a line per
    stage on stderr: for library code such as the learning environments, which run inside
    their user's program (that may not guard ``__main__`` as a spawned process would need)."""
    ensure(cache_directory(), STAGES, keys, _say, in_child=False)
