"""What a run records: trajectories (one row per logging step) and events, and their files.

:class:`SimulationLog` (:mod:`~hcomc.sim.log.simulation_log`) is what every engine returns;
:mod:`~hcomc.sim.log.data` reads it (arrays, slot columns, vehicles' rows),
:mod:`~hcomc.sim.log.events` holds the event table, :mod:`~hcomc.sim.log.layout` and
:mod:`~hcomc.sim.log.slots` the row and column layout the compiled step writes,
:mod:`~hcomc.sim.log.files` the ``.npz``/``.parquet`` files, and :mod:`~hcomc.sim.log.plans`
the typed records of the merge plans a run kept.
"""

from hcomc.sim.log.events import EVENT_DTYPE, EventKind
from hcomc.sim.log.files import LOG_FILES, log_file_of
from hcomc.sim.log.simulation_log import SimulationLog

__all__ = ["EVENT_DTYPE", "LOG_FILES", "EventKind", "SimulationLog", "log_file_of"]
