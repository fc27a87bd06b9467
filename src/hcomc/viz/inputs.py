"""Figure inputs from files or scenarios, and :func:`make_figure`, the entry point of
``hcomc plot``.

==============  ===============================================================================
kind            inputs (``sources``)
==============  ===============================================================================
contour         simulation logs (``log.npz`` / ``.parquet`` or the ``--out`` directory of
                ``hcomc simulate``), one column each; or one scenario (preset name or TOML
                file, or a corridor of the paper's layout such as ``paper``), simulated with
                FIFO, Game and HCOMC (without a controller when the scenario has no merge,
                e.g. ``platoon``)
timespace       one simulation log, or one scenario (simulated with HCOMC)
trajectories    one simulation log, or one scenario (simulated with HCOMC)
pareto          plan reports (JSON of ``hcomc plan --json``; a file may also hold a mapping
                optimiser -> report), or one scenario (decided by NSGA-II, PSO and SA)
metrics         one runs table (``runs.parquet`` / ``runs.csv`` or a results directory
                holding one)
==============  ===============================================================================

A scenario may be a corridor of the paper's layout: it is simulated in the scenario engine,
as ``hcomc simulate`` runs it (:func:`hcomc.corridor.engine.scenario_config`). Corridor runs
and the corridors run as corridors are drawn by the corridor kinds of
:mod:`hcomc.viz.corridor_inputs` (``speed_heatmap``, ``flow_density``, ``travel_times``);
these kinds refuse them.

Bad input raises :class:`ValueError` with a one-line message naming the source and what is
allowed (the CLI prints it and exits with status 2).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hcomc.corridor.engine import scenario_config
from hcomc.viz.sources import Source, is_scenario

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from hcomc.sim.log import SimulationLog

__all__ = [
    "CONTOUR_CONFIGURATIONS",
    "FIGURE_KINDS",
    "PARETO_OPTIMIZERS",
    "controller_logs",
    "decision_reports",
    "load_log",
    "load_reports",
    "load_runs",
    "make_figure",
]

FIGURE_KINDS: dict[str, str] = {
    "contour": "speed contour maps of both main lanes per controller (paper Fig. 2)",
    "timespace": "time-space diagram per lane, coloured by speed",
    "trajectories": "merge paths of VR and VMC; v(t), a(t) of the six key vehicles",
    "pareto": "Pareto set of one merge decision with the chosen plans of each optimiser",
    "metrics": "the paper's five metrics per condition and configuration, 95 % CI",
}
"""Figure kind -> one-line description (the choices of ``hcomc plot --kind``)."""

CONTOUR_CONFIGURATIONS: tuple[str, ...] = ("FIFO", "Game", "HCOMC")
"""Configurations simulated when a contour map is asked for a scenario."""

PARETO_OPTIMIZERS: tuple[str, ...] = ("nsga2", "pso", "sa")
"""Optimisers run when a Pareto figure is asked for a scenario."""

_RUNS_NAMES = ("runs.parquet", "runs.csv")


# --------------------------------------------------------------------------- loading
def load_log(source: Source) -> SimulationLog:
    """A simulation log from a ``.npz``/``.parquet`` file or a ``hcomc simulate --out`` dir.

    Raises
    ------
    ValueError
        If the source does not exist, is a directory without ``log.npz``/``log.parquet``,
        or has another suffix.
    """
    from hcomc.sim.log import SimulationLog, log_file_of

    return SimulationLog.load(log_file_of(source))


def load_runs(source: Source) -> pd.DataFrame:
    """A runs table from ``.parquet``/``.csv`` or a directory holding ``runs.parquet``/``.csv``.

    Raises
    ------
    ValueError
        If no such file exists or the suffix is another one.
    """
    import pandas as pd

    path = Path(source)
    if path.is_dir():
        found = [path / name for name in _RUNS_NAMES if (path / name).is_file()]
        if not found:
            raise ValueError(f"directory '{path}' holds no {' or '.join(_RUNS_NAMES)}")
        path = found[0]
    if not path.is_file():
        raise ValueError(f"runs table '{path}' does not exist")
    suffix = path.suffix.lower()
    if suffix == ".parquet":
        return pd.read_parquet(path)
    if suffix == ".csv":
        return pd.read_csv(path)
    raise ValueError(f"runs table '{path}' has suffix '{path.suffix}'; allowed: .parquet, .csv")


def load_reports(sources: Sequence[Source]) -> dict[str, dict[str, Any]]:
    """Plan reports from JSON files, keyed by optimiser.

    A file holds one report (``hcomc plan --json``; keyed by its ``optimizer``) or a
    mapping name -> report.

    Raises
    ------
    ValueError
        If a file is missing, is not JSON, or holds no plan report.
    """
    reports: dict[str, dict[str, Any]] = {}
    for source in sources:
        path = Path(source)
        if path.is_dir():
            raise ValueError(
                f"'{path}' is a directory, but a Pareto figure needs a plan report: the JSON "
                "of 'hcomc plan CONFIG --json > plan.json', or a preset name to decide"
            )
        if not path.is_file():
            raise ValueError(f"plan report '{path}' does not exist")
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise ValueError(f"plan report '{path}' is not JSON: {exc}") from None
        if isinstance(data, dict) and "pareto" in data:
            items = {str(data.get("optimizer") or path.stem): data}
        elif (
            isinstance(data, dict)
            and data
            and all(isinstance(v, dict) and "pareto" in v for v in data.values())
        ):
            items = {str(k): v for k, v in data.items()}
        else:
            raise ValueError(
                f"'{path}' holds no plan report (expected the JSON of 'hcomc plan --json' or "
                "a mapping optimiser -> report)"
            )
        for key, rep in items.items():
            name, k = key, 2
            while name in reports:
                name, k = f"{key}-{k}", k + 1
            reports[name] = rep
    return reports


# --------------------------------------------------------------------------- scenarios
def controller_logs(
    scenario: Source,
    *,
    seed: int | None = None,
    configurations: Sequence[str] = CONTOUR_CONFIGURATIONS,
    duration: float | None = None,
    overrides: dict[str, Any] | None = None,
) -> dict[str, SimulationLog]:
    """Simulate one scenario and seed with several configurations (common random numbers),
    each as ``hcomc run`` and ``hcomc reproduce`` run it (FIFO, Game and HCOMC plan once,
    FIFO-R, Game-R and HCOMC-R replan: :func:`hcomc.experiments.runner.configuration_overrides`).

    Parameters
    ----------
    scenario : str or os.PathLike
        Preset name (``C1`` ... ``C5``), TOML file or corridor of the paper's layout
        (:func:`hcomc.corridor.engine.scenario_config`).
    seed : int or None
        Run seed; default the config's.
    configurations : sequence of str
        Labels of :data:`hcomc.experiments.runner.CONFIGURATIONS`.
    duration : float or None
        Measured duration [s]; default the config's.
    overrides : dict or None
        Config overrides of every run (nested, as :func:`hcomc.config.nest_overrides` gives
        them), e.g. those of ``hcomc reproduce --set``.

    Returns
    -------
    dict of str to SimulationLog
        Configuration label -> log, in the given order.

    Raises
    ------
    hcomc.config.ConfigError
        On a bad scenario.
    ValueError
        On an unknown configuration label.
    """
    from hcomc.experiments.runner import CONFIGURATIONS, configuration_overrides
    from hcomc.sim.engine import simulate

    unknown = [c for c in configurations if c not in CONFIGURATIONS]
    if unknown:
        raise ValueError(
            f"unknown configuration(s) {unknown}; allowed: {', '.join(CONFIGURATIONS)}"
        )
    settings = {**(overrides or {})}
    if duration is not None:
        settings["duration"] = duration
    logs: dict[str, SimulationLog] = {}
    for label in configurations:
        config = scenario_config(scenario, **configuration_overrides(label, settings))
        logs[label] = simulate(config, seed)
    return logs


def decision_reports(
    scenario: Source,
    *,
    seed: int | None = None,
    optimizers: Sequence[str] = PARETO_OPTIMIZERS,
) -> dict[str, dict[str, Any]]:
    """Plan reports of the first HCOMC decision of a scenario, one per optimiser.

    Raises
    ------
    hcomc.config.ConfigError
        On a bad scenario or optimiser.
    ValueError
        If no ramp vehicle reaches the control zone within the run.
    """
    from hcomc.control.report import plan_report
    from hcomc.sim.engine import Simulation

    reports: dict[str, dict[str, Any]] = {}
    for opt in optimizers:
        config = scenario_config(scenario, control={"controller": "hcomc", "optimizer": opt})
        sim = Simulation(config, seed)
        plan = sim.run_until_plan()
        if plan is None:
            raise ValueError(
                f"no ramp vehicle entered the control zone within duration = {config.duration} s "
                f"of '{scenario}'; allowed: a scenario with ramp demand"
            )
        reports[opt] = plan_report(sim, plan)
    return reports


def _has_merge(scenario: Source) -> bool:
    """Whether a scenario has ramp vehicles that merge (so controllers can be compared)."""
    config = scenario_config(scenario)
    return config.scenario == "merge" and config.demand.ramp != "none"


def _labelled(logs: Sequence[SimulationLog]) -> dict[str, SimulationLog]:
    from hcomc.viz.common import configuration_label

    out: dict[str, SimulationLog] = {}
    for log in logs:
        label = base = configuration_label(log)
        k = 2
        while label in out:
            label, k = f"{base} ({k})", k + 1
        out[label] = log
    return out


# --------------------------------------------------------------------------- dispatch
def make_figure(
    kind: str,
    sources: Sequence[Source],
    *,
    seed: int | None = None,
    **options: Any,
) -> Figure:
    """Build one figure of *kind* from files or a scenario (module docstring table).

    Parameters
    ----------
    kind : str
        One of :data:`FIGURE_KINDS`.
    sources : sequence of str or os.PathLike
        Input files/directories, or one scenario (preset name or TOML file, or a corridor
        of the paper's layout).
    seed : int or None
        Seed when a scenario is simulated; default the config's. Ignored for files.
    **options
        Passed to the figure function (e.g. ``dx``, ``dt_bin``, ``smooth`` for contour,
        ``safety_threshold`` for pareto, ``metrics`` for metrics).

    Returns
    -------
    matplotlib.figure.Figure
        The figure; write it with :func:`hcomc.viz.common.save_figure`.

    Raises
    ------
    ValueError
        On an unknown kind, a wrong number of sources or unusable input (among it a
        corridor run or a corridor of a corridor run:
        :func:`hcomc.viz.corridor_inputs.refuse_corridor_input`).
    hcomc.config.ConfigError
        On a bad scenario.
    """
    from hcomc.viz.corridor_inputs import refuse_corridor_input
    from hcomc.viz.figures import (
        contour_figure,
        metrics_figure,
        pareto_figure,
        timespace_figure,
        trajectories_figure,
    )

    if kind not in FIGURE_KINDS:
        raise ValueError(f"unknown figure kind '{kind}'; allowed: {', '.join(FIGURE_KINDS)}")
    sources = list(sources)
    refuse_corridor_input(kind, sources)
    if not sources:
        raise ValueError(f"figure kind '{kind}' needs at least one input")
    scenario = len(sources) == 1 and is_scenario(sources[0])
    if kind not in {"contour", "pareto"} and len(sources) != 1:
        raise ValueError(f"figure kind '{kind}' takes exactly one input, got {len(sources)}")

    if kind == "contour":
        if scenario and not _has_merge(sources[0]):  # no merge: nothing for controllers to do
            from hcomc.sim.engine import simulate

            logs = {"no controller": simulate(scenario_config(sources[0]), seed)}
        elif scenario:
            logs = controller_logs(sources[0], seed=seed)
        else:
            logs = _labelled([load_log(s) for s in sources])
        return contour_figure(logs, **options)
    if kind in ("timespace", "trajectories"):
        if scenario:
            log = controller_logs(sources[0], seed=seed, configurations=("HCOMC",))["HCOMC"]
        else:
            log = load_log(sources[0])
        fn = timespace_figure if kind == "timespace" else trajectories_figure
        return fn(log, **options)
    if kind == "pareto":
        reports = decision_reports(sources[0], seed=seed) if scenario else load_reports(sources)
        return pareto_figure(reports, **options)
    if scenario:
        raise ValueError(
            f"figure kind 'metrics' needs a runs table (runs.parquet/.csv or a results "
            f"directory), got scenario '{sources[0]}'"
        )
    return metrics_figure(load_runs(sources[0]), **options)
