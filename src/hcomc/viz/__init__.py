"""Static figures of simulation logs, merge decisions and results tables.

The only part of :mod:`hcomc` that imports matplotlib. Every figure is built with the
object-oriented API on a fresh :class:`matplotlib.figure.Figure` (no ``pyplot`` state, no
display needed), so figures can be made concurrently in threads or worker processes.

Modules
-------
:mod:`hcomc.viz.common`
    Saving (:func:`~hcomc.viz.common.save_figure`), road geometry, zone shading, colours.
:mod:`hcomc.viz.figures`
    One function per figure kind: :func:`~hcomc.viz.figures.contour_figure` (paper Fig. 2),
    :func:`~hcomc.viz.figures.timespace_figure`, :func:`~hcomc.viz.figures.trajectories_figure`,
    :func:`~hcomc.viz.figures.pareto_figure`, :func:`~hcomc.viz.figures.metrics_figure`.
:mod:`hcomc.viz.inputs`
    Loading a figure's input from files and :func:`~hcomc.viz.inputs.make_figure`, the
    one-call entry point for ``hcomc plot``.
:mod:`hcomc.viz.replay`
    The interactive replay of runs in the browser: :func:`replay` builds the page (and
    :func:`~hcomc.viz.replay.write_replay` writes it); no matplotlib.

The public names below are imported lazily on first access, so ``import hcomc.viz`` is cheap
(:func:`replay` is bound at import, so that the name is the function and not its package;
importing it costs only the standard library).
"""

from __future__ import annotations

import importlib
from typing import Any

from hcomc.viz.replay import replay

__all__ = [
    "FIGURE_KINDS",
    "contour_figure",
    "make_figure",
    "metrics_figure",
    "pareto_figure",
    "replay",
    "save_figure",
    "timespace_figure",
    "trajectories_figure",
]

_LAZY = {
    "FIGURE_KINDS": "hcomc.viz.inputs",
    "make_figure": "hcomc.viz.inputs",
    "save_figure": "hcomc.viz.common",
    "contour_figure": "hcomc.viz.figures",
    "metrics_figure": "hcomc.viz.figures",
    "pareto_figure": "hcomc.viz.figures",
    "timespace_figure": "hcomc.viz.figures",
    "trajectories_figure": "hcomc.viz.figures",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
