"""Runs and comparisons from Python: :func:`run` and :func:`compare`, the library
counterparts of ``hcomc run`` and ``hcomc compare --controllers``.

:func:`run` runs one scenario (or corridor) with one merge controller over seeds and returns
the table of its runs, one row each (the rows ``hcomc run --json`` prints). :func:`compare`
runs cells of a benchmark suite x configurations x seeds, paired by seed, and returns a
:class:`ComparisonResult`: the runs and the tables ``hcomc compare`` prints and writes (merge
success, its paired comparison, each configuration's means and the paired effects). Both build
the command line's run specs and run them with its runner
(:func:`~hcomc.experiments.runner.run_grid`), and a comparison's tables are the command's
(:func:`~hcomc.experiments.comparison.analysis.comparison_tables`), so the numbers are the
command's. Everything stays in memory: the resumable results folder, its files and report
are the command line's (``hcomc compare --out``).

A controller is named as on the command line (a registered name, ``package.module:Class``,
``path/to/file.py:Class``; in :func:`compare` also a label such as ``HCOMC-R``) or given as
its class, which stands for its module's spec (every run builds its own controller from its
config, so an instance will not do). Bad input raises :class:`~hcomc.config.ConfigError`
naming the argument, the value and what is allowed, before anything runs. Progress goes only
to a ``progress(done, total)`` callback. ``workers`` > 1 runs in that many fresh (spawned)
processes: in a script, call from under ``if __name__ == "__main__":``.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any

import pandas as pd

from hcomc.config import ConfigError, load_config, nest_overrides
from hcomc.corridor import is_corridor_source, load_corridor
from hcomc.experiments.benchmark import Comparison
from hcomc.experiments.comparison.analysis import comparison_tables
from hcomc.experiments.comparison.effects import pairs
from hcomc.experiments.controller_arguments import (
    Controller,
    baseline_label,
    configuration_labels,
    controller_name,
)
from hcomc.experiments.runner import (
    ENGINES,
    configuration_of,
    grid,
    run_grid,
)
from hcomc.experiments.suite import LATEST, suite_named

__all__ = ["ComparisonResult", "Progress", "compare", "run"]

Progress = Callable[[int, int], None]
"""A progress callback: ``progress(done, total)`` after each finished run."""


@dataclass(frozen=True, eq=False)
class ComparisonResult:
    """What :func:`compare` ran and found; every configuration by the name the tables show.

    The tables are those of ``hcomc compare`` (its CSV files): ``success`` (merge success,
    k of n runs per cell and configuration), ``success_pairs`` (merge success of A against
    B, paired by seed), ``means`` (per cell, configuration and metric: mean, 95 % t
    half-width, n), ``effects`` (per cell, comparison and metric: the paired effect of A
    against B, its CI, verdicts and sign test) and ``safety`` (per cell and configuration: the
    least TTC and largest DRAC over the runs, with their seeds, and the collisions); their
    columns are the fields of :class:`~hcomc.experiments.comparison.success.Success`,
    :class:`~hcomc.experiments.comparison.success.SuccessPair`,
    :class:`~hcomc.experiments.comparison.means.Mean`,
    :class:`~hcomc.experiments.comparison.effects.Effect` and
    :class:`~hcomc.experiments.comparison.safety.SafetyExtremes`. ``runs`` has a row per run
    (cell, configuration, seed): ``suite``, ``condition`` (the cell), ``base``, ``engine``,
    then the columns of :func:`hcomc.run`.
    """

    suite: str  # the suite's name, e.g. "merge-v1"
    cells: tuple[str, ...]
    configurations: tuple[str, ...]
    seeds: int  # seeds 0 .. seeds-1 in every cell
    comparisons: tuple[tuple[str, str], ...]  # (A, B) pairs, A compared with B
    names: dict[str, str]  # spec -> name, for controllers named by module or file
    overrides: dict[str, Any]  # nested config overrides of every run
    engine: str
    runs: pd.DataFrame
    success: pd.DataFrame
    success_pairs: pd.DataFrame
    means: pd.DataFrame
    effects: pd.DataFrame
    safety: pd.DataFrame

    def __repr__(self) -> str:
        return (
            f"ComparisonResult(suite={self.suite!r}, cells={self.cells}, "
            f"configurations={self.configurations}, seeds={self.seeds}, runs={len(self.runs)})"
        )


def run(
    config: str | os.PathLike[str],
    controller: Controller | None = None,
    *,
    seeds: int = 1,
    optimizer: str | None = None,
    overrides: Mapping[str, Any] | None = None,
    engine: str = "hcomc",
    workers: int = 1,
    progress: Progress | None = None,
) -> pd.DataFrame:
    """Run a scenario with one merge controller over seeds 0 .. ``seeds``-1: ``hcomc run``.

    Parameters
    ----------
    config : str or path
        A preset (``C1`` .. ``C5``) or scenario TOML file; or a corridor (preset or file),
        which runs as ``hcomc run CORRIDOR`` does.
    controller : str or class, optional
        The merge controller (default: the config's ``control.controller``).
    seeds : int
        Number of seeds.
    optimizer : str, optional
        HCOMC's optimiser (``nsga2``, ``pso``, ``sa``, ...); only with HCOMC.
    overrides : mapping, optional
        Config values for every run, as :func:`~hcomc.config.load_config` takes them (flat,
        dotted or nested); dotted corridor keys for a corridor.
    engine : str
        ``hcomc``, or ``sumo`` (SUMO co-simulation, extra ``hcomc[sumo]``).
    workers : int
        Processes (1: this one).
    progress : callable, optional
        Called as ``progress(done, total)`` after each run.

    Returns
    -------
    pandas.DataFrame
        One row per seed: the configuration, the plan, the paper's metrics and the outcome
        (for a corridor as a corridor run, the corridor metrics).
    """
    _check_count("seeds", seeds)
    _check_count("workers", workers)
    _check_engine(engine)
    source = os.fspath(config)
    settings = dict(overrides or {})
    if optimizer is not None:  # checked by the config, like a file's value
        settings["control.optimizer"] = optimizer.lower()
    name = None if controller is None else controller_name(controller)
    what = _run_corridor if is_corridor_source(source) else _run_scenario
    return what(source, name, optimizer, seeds, settings, engine, workers, progress)


def _run_scenario(
    source: str, name: str | None, optimizer: str | None, seeds: int,
    settings: dict[str, Any], engine: str, workers: int, progress: Progress | None,
) -> pd.DataFrame:  # fmt: skip
    """:func:`run` on a scenario: ``hcomc run CONFIG``'s runs."""
    base = load_config(source, **settings)
    if base.scenario != "merge" or base.demand.ramp == "none":
        raise ConfigError(
            f"argument 'config' = '{source}' has no merge to control (scenario = "
            f"'{base.scenario}', demand.ramp = '{base.demand.ramp}'); allowed: a merge scenario "
            "with ramp demand (C1..C5, or demand.ramp = 'single' or 'flow')"
        )
    label = _run_label(base.control.model_dump(), source, name, optimizer)
    specs = grid([source], [label], range(seeds), nest_overrides(settings))
    return run_grid([replace(s, engine=engine) for s in specs], workers=workers,
                    progress=progress)  # fmt: skip


def _run_corridor(
    source: str, name: str | None, optimizer: str | None, seeds: int,
    settings: dict[str, Any], engine: str, workers: int, progress: Progress | None,
) -> pd.DataFrame:  # fmt: skip
    """:func:`run` on a corridor: ``hcomc run CORRIDOR``'s runs."""
    from hcomc.experiments.corridor.runs import CorridorSpec, check
    from hcomc.experiments.workers import run_rows

    corridor = load_corridor(source, settings)
    label = _run_label(corridor.control.model_dump(), source, name, optimizer)
    specs = [CorridorSpec(source, label, seed, settings, engine) for seed in range(seeds)]
    with _as_arguments():
        check(specs[0])
    return run_rows(specs, workers=workers, progress=progress)


def _run_label(
    control: dict[str, Any], source: str, name: str | None, optimizer: str | None
) -> str:
    """The configuration :func:`run` runs: ``control`` (a config's table, with the optimiser
    given) with the controller given; ConfigError when none is named or an optimiser is
    given to another controller than HCOMC."""
    controller = name or control["controller"]
    if controller == "none":
        raise ConfigError(
            f"argument 'controller' = None: '{source}' has control.controller = 'none'; "
            "allowed: a controller name, or a config that names one"
        )
    if optimizer is not None and controller != "hcomc":
        raise ConfigError(
            f"argument 'optimizer' = '{optimizer}' does not apply to controller "
            f"'{controller}'; allowed: an optimizer only with controller 'hcomc'"
        )
    return configuration_of({**control, "controller": controller})


def compare(
    controllers: str | Sequence[Controller],
    *,
    conditions: str | Sequence[str] | None = None,
    seeds: int | None = None,
    suite: str = LATEST,
    baseline: Controller | None = None,
    overrides: Mapping[str, Any] | None = None,
    engine: str = "hcomc",
    workers: int = 1,
    progress: Progress | None = None,
) -> ComparisonResult:
    """Compare merge controllers on cells of a benchmark suite, paired by seed:
    ``hcomc compare --controllers``.

    Parameters
    ----------
    controllers : str or sequence
        Two or more configurations: labels (``fifo``, ``game``, ``hcomc``, ``HCOMC-R``, ...),
        controller names or classes; a string is split at commas (``"fifo,hcomc"``).
    conditions : str or sequence of str, optional
        Cells of the suite: ids and ranges (``["C1", "C2"]``, ``"C1..C5"``); default: all.
    seeds : int, optional
        Seeds 0 .. N-1 per cell (default: the suite's, 30).
    suite : str
        The benchmark suite (default: the latest, ``merge-v1``).
    baseline : str or class, optional
        Compare every configuration with this one only (default: every pair, each with
        those before it).
    overrides : mapping, optional
        Config values for every cell, as :func:`~hcomc.config.load_config` takes them.
    engine : str
        ``hcomc``, or ``sumo`` (SUMO co-simulation, extra ``hcomc[sumo]``).
    workers : int
        Processes (1: this one).
    progress : callable, optional
        Called as ``progress(done, total)`` after each run.

    Returns
    -------
    ComparisonResult
        The runs and the tables of the comparison.
    """
    _check_count("workers", workers)
    with _as_arguments():
        plan = _comparison(controllers, conditions, seeds, suite, overrides, engine)
        chosen = None if baseline is None else baseline_label(baseline, plan.configurations)
    tables = comparison_tables(
        _comparison_runs(plan, workers, progress),
        plan.configurations,
        pairs(plan.configurations, chosen),
    )
    return ComparisonResult(
        suite=plan.suite.name, cells=tuple(c.id for c in plan.cells),
        configurations=tables.configurations, seeds=plan.seeds,
        comparisons=tables.comparisons, names=tables.names, overrides=plan.overrides,
        engine=plan.engine, runs=tables.runs, success=tables.success,
        success_pairs=tables.success_pairs, means=tables.means, effects=tables.effects,
        safety=tables.safety,
    )  # fmt: skip


def _comparison(
    controllers: str | Sequence[Controller],
    conditions: str | Sequence[str] | None,
    seeds: int | None,
    suite: str,
    overrides: Mapping[str, Any] | None,
    engine: str,
) -> Comparison:
    """The comparison :func:`compare` runs, every cell loaded with every configuration."""
    labels = configuration_labels(controllers)
    if seeds is not None:
        _check_count("seeds", seeds)
    _check_engine(engine)
    bench = suite_named(suite)
    if conditions is not None and not isinstance(conditions, str):
        conditions = ",".join(conditions)
    cells = bench.select(conditions)
    plan = Comparison(bench, cells, tuple(labels), seeds or bench.seeds,
                      nest_overrides(dict(overrides or {})), engine)  # fmt: skip
    plan.check()
    if engine == "sumo":
        from hcomc.sumo.routes import sumo_problem

        problem = sumo_problem(cells[0].config(**plan.overrides))
        if problem is not None:
            raise ConfigError(f"argument 'engine' = 'sumo': {problem}")
    return plan


def _comparison_runs(plan: Comparison, workers: int, progress: Progress | None) -> pd.DataFrame:
    """The runs of ``plan`` in its order (cell, configuration, seed), each row headed by its
    cell as the command line's runs table."""
    runs = plan.runs()
    rows: list[dict[str, Any]] = [{} for _ in runs]

    def keep(i: int, row: dict[str, Any], _manifest: dict[str, Any]) -> None:
        rows[i] = plan.row(runs[i][0], row)

    run_grid([spec for _, spec in runs], workers=workers, progress=progress, on_result=keep)
    return pd.DataFrame(rows)


def _check_count(argument: str, value: object) -> None:
    """ConfigError unless ``value`` (seeds, workers) is a whole number of at least 1."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ConfigError(f"argument '{argument}' = {value!r}: allowed: an integer >= 1")


def _check_engine(engine: str) -> None:
    """ConfigError unless ``engine`` names a simulation engine."""
    if engine not in ENGINES:
        raise ConfigError(f"argument 'engine' = {engine!r}: allowed: {', '.join(ENGINES)}")


_OPTION = re.compile(r"option '--([a-z]+)'")


@contextmanager
def _as_arguments() -> Iterator[None]:
    """ConfigErrors of the suite's selection name :func:`compare`'s arguments, not the
    command line's options (``option '--conditions'`` -> ``argument 'conditions'``)."""
    try:
        yield
    except ConfigError as exc:
        raise ConfigError(_OPTION.sub(r"argument '\1'", str(exc))) from None
