"""What ``hcomc run`` prints and which configuration it runs: a runs table on the terminal,
the configuration label of a ``[control]`` table, and the runs of the scenario engine with
their means. Shared by ``hcomc run`` on scenarios (:mod:`hcomc.cli.experiments`), on corridors
(:mod:`hcomc.cli.corridor_conditions`) and ``hcomc reproduce``."""

from __future__ import annotations

from typing import Any

from rich.markup import escape
from rich.table import Table

from hcomc.cli._app import _control, _fail, out


def _frame_table(frame: Any, title: str) -> Table:
    """A rich table of ``frame``: the columns of names (``claim``, ``Model``) left-aligned,
    the others right-aligned, floats with two decimals."""
    table = Table(title=escape(title))
    for col in frame.columns:
        table.add_column(escape(str(col)), justify="left" if col in ("claim", "Model") else "right")
    for _, row in frame.iterrows():
        table.add_row(*(escape(f"{v:.2f}" if isinstance(v, float) else str(v)) for v in row))
    return table


def run_label(
    table: Any, source: str, controller: str | None, optimizer: str | None,
    overrides: dict[str, Any], what: str,
) -> str:  # fmt: skip
    """The configuration ``hcomc run`` runs on ``source`` (a ``what``, whose control table
    is ``table``): ``--controller`` / ``--optimizer`` or the table's; a one-line error when
    neither names a controller. A given optimiser is kept in ``overrides``
    (``control.optimizer``) for a controller name that is not a paper label."""
    control = _control(table, controller, optimizer)
    if control["controller"] == "none":
        raise _fail(
            f"no merge controller: '{source}' has control.controller = 'none'; allowed: "
            f"--controller NAME, or a {what} that names one"
        )
    if optimizer is not None:
        overrides["control.optimizer"] = control["optimizer"]
    return configuration_of(control)


def configuration_of(control: dict[str, Any]) -> str:
    """The configuration label a ``[control]`` table's controller and optimiser stand for
    (``fifo`` is FIFO, planning once as published; HCOMC with PSO is HCOMC-PSO), else the
    controller's name."""
    from hcomc.experiments.runner import CONFIGURATIONS

    labels = {pair: label for label, pair in CONFIGURATIONS.items()}
    name = control["controller"]
    return labels.get((name, control["optimizer"] if name == "hcomc" else "nsga2"), name)


def print_merge_runs(frame: Any, title: str, duration: float) -> None:
    """Print runs of the scenario engine: per seed the paper's metrics, merge success, and
    each metric's mean with its 95 % CI."""
    from hcomc.experiments.tables import LABELS, mean_ci

    frame = frame.reindex(columns=[*frame.columns, *(m for m in LABELS if m not in frame)])
    cols = ["seed", "merged", "mode", "decision_ms", *LABELS]
    out.print(_frame_table(frame[cols].rename(columns=LABELS), title))
    merged = frame["merged"].fillna(False).astype(bool)
    out.print(
        f"VR merged in {int(merged.sum())} of {len(frame)} runs; a run in which it did not is "
        "an outcome, not a run without disturbance: its metrics of the merge are empty",
        highlight=False,
    )
    unplanned = frame.loc[frame["mode"] == "", "seed"].tolist()
    if unplanned:
        out.print(
            f"no merge planned in seed(s) {unplanned}: no ramp vehicle entered the control "
            f"zone within duration = {duration} s, so these seeds have no metrics"
        )
    for metric, name in LABELS.items():
        mean, half, n = mean_ci(frame[metric].dropna())
        out.print(escape(f"{name}: {mean:.4g} ± {half:.2g} (95 % CI, n = {n})"))
