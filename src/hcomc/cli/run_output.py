"""What ``hcomc run`` prints and which configuration it runs: a runs table on the terminal,
the configuration label of a ``[control]`` table, and the runs of the scenario engine with
their means. Shared by ``hcomc run`` on scenarios (:mod:`hcomc.cli.experiments`), on corridors
(:mod:`hcomc.cli.corridor_conditions`) and ``hcomc reproduce``."""

from __future__ import annotations

import math
from typing import Any

from rich.markup import escape

from hcomc.cli._app import _control, _fail, out
from hcomc.viz.text_tables import TextTable, print_fitted

NAMES = ("claim", "Model", "cell", "condition", "Condition", "configuration", "mode", "sequence")
"""Columns of names and words, left-aligned (the others, numbers, right-aligned)."""


def _cell(value: Any) -> str:
    """A table cell: a float to three significant digits ("—" for NaN), a flag as yes/no,
    anything else as text."""
    from hcomc.experiments.comparison.view import rounded

    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return rounded(value)
    return str(value)


def mean_line(name: str, values: Any) -> str:
    """One mean as a line, "name: mean ± half-width (95 % CI, n = n)", rounded to the
    half-width ("name: mean (n = 1)" without an interval)."""
    from hcomc.experiments.comparison.view import rounded
    from hcomc.experiments.tables import mean_ci

    mean, half, n = mean_ci(values)
    if math.isnan(half):  # fewer than two values: no interval
        return f"{name}: {rounded(mean)} (n = {n})"
    return f"{name}: {rounded(mean, half)} ± {rounded(half, half)} (95 % CI, n = {n})"


def print_frame(frame: Any, title: str, caption: str = "", keys: int = 1) -> None:
    """Print ``frame`` as a booktabs-style table fitted to 120 columns or a narrower terminal
    (:func:`~hcomc.viz.text_tables.print_fitted`: in blocks of columns led by its first
    ``keys`` columns when wider), its cells as :func:`_cell` writes them and ``caption`` (its
    legend) under it."""
    text = frame.map(_cell)
    numeric = tuple(c for c in frame.columns if c not in NAMES)
    print_fitted(out, TextTable(text, title, caption, numeric), keys)


def run_label(
    table: Any, source: str, controller: str | None, optimizer: str | None,
    overrides: dict[str, Any], what: str,
) -> str:  # fmt: skip
    """The configuration ``hcomc run`` runs on ``source`` (a ``what``, whose control table
    is ``table``): ``--controller`` / ``--optimizer`` or the table's; a one-line error when
    neither names a controller. A given optimiser is kept in ``overrides``
    (``control.optimizer``) for a controller name that is not a paper label."""
    from hcomc.experiments.runner import configuration_of

    control = _control(table, controller, optimizer)
    if control["controller"] == "none":
        raise _fail(
            f"no merge controller: '{source}' has control.controller = 'none'; allowed: "
            f"--controller NAME, or a {what} that names one"
        )
    if optimizer is not None:
        overrides["control.optimizer"] = control["optimizer"]
    return configuration_of(control)


RUN_LEGEND = (
    "decision: the controller's time for its first plan; least TTC and max DRAC: over every "
    "follower-leader pair of a lane with a key vehicle in it (a least TTC of ∞: no pair closed "
    "in; a max DRAC of ∞: a pair overlapped)"
)
"""The legend of ``hcomc run``'s table of scenario runs."""


def print_merge_runs(frame: Any, title: str, duration: float) -> None:
    """Print runs of the scenario engine: per seed the paper's metrics, merge success, and
    each metric's mean with its 95 % CI."""
    from hcomc.experiments.comparison.view import SAFETY_LABELS
    from hcomc.experiments.tables import LABELS

    shown = {**LABELS, **SAFETY_LABELS}
    frame = frame.reindex(columns=[*frame.columns, *(m for m in shown if m not in frame)])
    cols = ["seed", "merged", "mode", "decision_ms", *shown]
    print_frame(frame[cols].rename(columns={**shown, "decision_ms": "decision [ms]"}), title,
                RUN_LEGEND)  # fmt: skip
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
        out.print(escape(mean_line(name, frame[metric].dropna())), highlight=False)
