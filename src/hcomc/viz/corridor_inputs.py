"""Corridor figures of ``hcomc plot``: which input is a corridor, its tables, and
:func:`make_corridor_figure`.

==============  ===============================================================================
kind            inputs (``sources``: exactly one)
==============  ===============================================================================
speed_heatmap   a corridor run (the ``--out`` directory of ``hcomc simulate CORRIDOR``; its
                ``grid.csv``), or a corridor (preset name or TOML file), simulated
                (:func:`hcomc.metrics.corridor.simulate_corridor`)
flow_density    the same; ``detectors.csv``
travel_times    the same; ``trips.csv``
==============  ===============================================================================

A corridor of the paper's layout (preset ``paper``) runs in the scenario engine, as
``hcomc simulate`` runs it (:func:`hcomc.corridor.engine.scenario_of`): the scenario kinds of
:mod:`hcomc.viz.inputs` draw it, and the corridor kinds refuse it rather than draw a run of
another engine than the one ``hcomc simulate`` uses for it. Bad input raises
:class:`ValueError` with a one-line message naming ``--kind``, the input and what is allowed.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from hcomc.viz.corridor import CORRIDOR_KINDS, KIND_TABLES, corridor_figure
from hcomc.viz.sources import Source, is_scenario

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from hcomc.corridor import Corridor

__all__ = [
    "RUN_MARKER",
    "SCENARIO_KINDS",
    "TABLE_COLUMNS",
    "is_corridor",
    "is_corridor_run",
    "load_run_table",
    "make_corridor_figure",
    "refuse_corridor_input",
    "runs_in_scenario_engine",
]

RUN_MARKER = "corridor.toml"
"""The file every corridor run directory holds (``hcomc simulate CORRIDOR --out``), and a
scenario run directory does not (both write ``detectors.csv``)."""

SCENARIO_KINDS = ("contour", "timespace", "trajectories", "pareto")
"""Kinds of :mod:`hcomc.viz.inputs` that simulate a scenario, so also a corridor of the
paper's layout."""

TABLE_COLUMNS: dict[str, tuple[str, ...]] = {
    "grid": ("x0", "x1", "t0", "t1", "distance", "time"),
    "detectors": ("x", "lane", "begin", "end", "count", "flow", "harmonic_speed"),
    "trips": ("origin", "outcome", "travel_time"),
}
"""Columns each run table needs for its figure (:data:`hcomc.viz.corridor.KIND_TABLES`)."""


# --------------------------------------------------------------------------- classifying
def is_corridor_run(source: Source) -> bool:
    """A directory holding :data:`RUN_MARKER`: the ``--out`` of a corridor run."""
    path = Path(source)
    return path.is_dir() and (path / RUN_MARKER).is_file()


def is_corridor(source: Source) -> bool:
    """A corridor preset name or corridor TOML file (:func:`hcomc.corridor.is_corridor_source`).

    Existing files other than TOML (logs, tables) and directories are not, and are not
    read to find out."""
    from hcomc.corridor import is_corridor_source

    path = Path(source)
    if path.is_dir() or (path.exists() and path.suffix.lower() != ".toml"):
        return False
    return is_corridor_source(source)


def _scenario_engine(corridor: Corridor) -> bool:
    """Whether ``corridor`` has the paper's layout, so ``hcomc simulate`` runs it in the
    scenario engine (:func:`hcomc.corridor.engine.scenario_of` accepts it)."""
    from hcomc.config import ConfigError
    from hcomc.corridor.engine import scenario_of

    try:
        scenario_of(corridor)
    except ConfigError:
        return False
    return True


def runs_in_scenario_engine(source: Source) -> bool:
    """Whether ``source`` is a corridor (:func:`is_corridor`) of the paper's layout.

    Raises :class:`hcomc.config.ConfigError` if it is a corridor that does not load."""
    from hcomc.corridor import load_corridor

    return is_corridor(source) and _scenario_engine(load_corridor(source, {}))


def refuse_corridor_input(kind: str, sources: Sequence[Source]) -> None:
    """A ValueError if a figure kind that is not a corridor kind gets a corridor run or a
    corridor run as a corridor: those are drawn by :data:`CORRIDOR_KINDS` only."""
    allowed = f"allowed: {', '.join(CORRIDOR_KINDS)}"
    for source in sources:
        if is_corridor_run(source):
            raise ValueError(
                f"option '--kind' = '{kind}' does not apply to corridor run '{source}'; {allowed}"
            )
        if is_corridor(source) and not runs_in_scenario_engine(source):
            raise ValueError(
                f"option '--kind' = '{kind}' does not apply to corridor '{source}', which runs "
                f"as a corridor, not as one of the paper's conditions; {allowed}"
            )


def _not_a_corridor(kind: str, source: Source) -> ValueError:
    """The error for a corridor kind whose input is neither a corridor run nor a corridor."""
    from hcomc.corridor import corridor_preset_names

    path = Path(source)
    if path.is_dir():
        what = f"directory '{source}' is not a corridor run (it has no {RUN_MARKER})"
    elif path.suffix.lower() == ".toml" and not path.is_file():
        what = f"corridor file '{source}' does not exist"
    elif path.is_file():
        what = f"'{source}' is a file, not a corridor run directory or corridor TOML"
    elif is_scenario(source):
        what = f"'{source}' is a scenario preset, not a corridor"
    else:
        what = f"'{source}' does not exist and is no corridor preset"
    return ValueError(
        f"option '--kind' = '{kind}' draws a corridor run, but {what}; allowed: the --out "
        "directory of 'hcomc simulate CORRIDOR', a corridor preset "
        f"({', '.join(corridor_preset_names())}) or a corridor TOML file"
    )


# --------------------------------------------------------------------------- tables
def load_run_table(directory: Source, table: str) -> pd.DataFrame:
    """``<table>.csv`` of a corridor run directory, checked for :data:`TABLE_COLUMNS`.

    Raises ValueError if the file is missing, is not a CSV table or lacks a column."""
    import pandas as pd

    path = Path(directory) / f"{table}.csv"
    if not path.is_file():
        raise ValueError(f"corridor run '{directory}' has no {path.name}")
    try:
        frame = pd.read_csv(path, dtype={"origin": str})
    except ValueError as exc:  # pandas' parser errors and UnicodeDecodeError are ValueErrors
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ValueError(f"'{path}' is not a CSV table: {first}") from None
    missing = [c for c in TABLE_COLUMNS[table] if c not in frame.columns]
    if missing:
        raise ValueError(
            f"'{path}' lacks the column(s) {', '.join(missing)}; allowed: a {path.name} of "
            "'hcomc simulate CORRIDOR --out'"
        )
    return frame


def _simulated_table(kind: str, source: Source, seed: int | None) -> pd.DataFrame:
    """The table of *kind* of corridor *source* simulated as a corridor run."""
    from hcomc.corridor import load_corridor
    from hcomc.metrics.corridor import simulate_corridor
    from hcomc.robustness.impairments import listeners_of

    corridor = load_corridor(source, {})
    if _scenario_engine(corridor):
        raise ValueError(
            f"option '--kind' = '{kind}' does not apply to corridor '{source}': it has the "
            "paper's layout and runs in the scenario engine, as 'hcomc simulate' runs it; "
            f"allowed: {', '.join(SCENARIO_KINDS)}"
        )
    run = simulate_corridor(corridor, seed=seed, listeners=listeners_of(corridor))
    table: pd.DataFrame = getattr(run, KIND_TABLES[kind])
    return table


# --------------------------------------------------------------------------- dispatch
def make_corridor_figure(
    kind: str, sources: Sequence[Source], *, seed: int | None = None
) -> Figure:
    """The corridor figure of *kind* (:data:`hcomc.viz.corridor.CORRIDOR_KINDS`) of one
    corridor run directory, or of one corridor simulated with *seed* (default: its own).

    Drawn by :func:`hcomc.viz.corridor.corridor_figure`, the function that draws the
    figures of ``hcomc simulate CORRIDOR --out``, so both show the same for the same run.

    Raises
    ------
    ValueError
        On an unknown kind, not exactly one input, an input that is not a corridor run or a
        corridor of a corridor run, a missing or unreadable table, or a seed for a
        saved run.
    hcomc.config.ConfigError
        On a corridor that does not load.
    """
    if kind not in CORRIDOR_KINDS:
        raise ValueError(f"option '--kind' = '{kind}': allowed: {', '.join(CORRIDOR_KINDS)}")
    if len(sources) != 1:
        raise ValueError(f"figure kind '{kind}' takes exactly one input, got {len(sources)}")
    source = sources[0]
    if is_corridor_run(source):
        if seed is not None:
            raise ValueError(
                f"option '--seed' = {seed}: allowed only when a corridor is simulated; "
                f"corridor run '{source}' already has its seed"
            )
        table = load_run_table(source, KIND_TABLES[kind])
    elif is_corridor(source):
        table = _simulated_table(kind, source, seed)
    else:
        raise _not_a_corridor(kind, source)
    return corridor_figure(kind, table)
