"""``hcomc export trajectories RUN --format commonroad``: a run's directory to a CommonRoad file.

:func:`export_commonroad` reads the run (:func:`hcomc.commonroad.run.load_run`), builds the
scenario (:func:`hcomc.commonroad.scenario.build_scenario`), writes it and checks it against
CommonRoad's XML schema, and returns what it did as an :class:`ExportSummary`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from hcomc.commonroad.run import load_run
from hcomc.commonroad.scenario import OBSTACLE_IDS, build_scenario, write_scenario
from hcomc.commonroad.schema import schema_errors

__all__ = ["ExportSummary", "export_commonroad"]


@dataclass(frozen=True, slots=True)
class ExportSummary:
    """What an export wrote: the file, counts, VR's hcomc id (None without a planning
    problem), the run's row of time step 0, the vehicles ``strict`` left out, the time step
    [s], and the schema's objections (empty: the file passes CommonRoad's XSD)."""

    path: Path
    lanelets: int
    obstacles: int
    states: int
    vr: int | None
    first_row: int
    left_out: tuple[int, ...]
    dt: float
    schema_errors: tuple[str, ...]

    def line(self) -> str:
        """One line for the terminal."""
        text = (f"wrote {self.path} · {self.lanelets} lanelets, {self.obstacles} dynamic "
                f"obstacles ({self.states} states, dt = {self.dt:g} s)")  # fmt: skip
        if self.vr is not None:
            text += (f" · planning problem {OBSTACLE_IDS + self.vr} for VR (vehicle {self.vr}), "
                     f"time step 0 = t {self.first_row * self.dt:g} s of the run")  # fmt: skip
        if self.left_out:
            text += f" · {len(self.left_out)} vehicles entering after time step 0 left out"
        if not self.schema_errors:
            return text + " · valid against CommonRoad's XSD"
        if all(_start_or_problem(e) for e in self.schema_errors):
            return text + (" · not valid against CommonRoad's 2020a XSD (it requires a planning "
                           "problem and every obstacle to start at time step 0: "
                           "--planning-problem --strict)")  # fmt: skip
        return text + f" · not valid against CommonRoad's XSD: {self.schema_errors[0]}"


def _start_or_problem(error: str) -> bool:
    """Whether a schema error is one the 2020a XSD raises for an obstacle starting after time
    step 0 or a file without a planning problem (the documented two)."""
    return ("maxInclusive" in error and "('0')" in error) or "planningProblem" in error


def export_commonroad(source: Path, out: Path, *, planning_problem: bool = False,
                      strict: bool = False) -> ExportSummary:  # fmt: skip
    """Write the run of ``source`` (a ``hcomc simulate --out`` directory or log file) to
    ``out`` as CommonRoad XML; ``ValueError`` with a one-line reason if it cannot."""
    run = load_run(source)
    built = build_scenario(run, planning_problem=planning_problem, strict=strict)
    write_scenario(built, out, source=run.provenance)
    obstacles = built.scenario.dynamic_obstacles
    states = sum(1 + len(o.prediction.trajectory.state_list) for o in obstacles)
    return ExportSummary(
        path=out, lanelets=len(run.strips), obstacles=len(obstacles), states=states,
        vr=built.vr, first_row=built.first_row, left_out=built.left_out, dt=run.dt,
        schema_errors=tuple(schema_errors(out)),
    )  # fmt: skip
