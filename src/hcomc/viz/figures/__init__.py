"""Static figures: one function per figure kind, each returning a matplotlib ``Figure``.

==================== ========================================= ==============================
function             shows                                     input
==================== ========================================= ==============================
contour_figure       speed field v(x, t) per controller and    ``{label: SimulationLog}``
                     main lane (paper Fig. 2)
timespace_figure     x(t) of every vehicle per lane, coloured  ``SimulationLog``
                     by speed; key vehicles and events marked
trajectories_figure  y-x paths of VR and VMC; v(t), a(t) of    ``SimulationLog``
                     the six key vehicles
pareto_figure        NSGA-II Pareto set in objective space,    ``{optimiser: plan_report}``
                     chosen plans of every optimiser
metrics_figure       the paper's five metrics, mean and 95 %   runs ``DataFrame``
                     CI per condition and configuration
==================== ========================================= ==============================

Figures are built with the object-oriented API on fresh :class:`~matplotlib.figure.Figure`
objects (see :func:`hcomc.viz.common.new_figure`); write them with
:func:`hcomc.viz.common.save_figure`.
"""

from hcomc.viz.figures.contour import LOW_SPEED_MARGIN, contour_figure
from hcomc.viz.figures.metrics import METRIC_TITLES, metrics_figure
from hcomc.viz.figures.pareto import pareto_figure
from hcomc.viz.figures.timespace import timespace_figure
from hcomc.viz.figures.trajectories import trajectories_figure

__all__ = [
    "LOW_SPEED_MARGIN",
    "METRIC_TITLES",
    "contour_figure",
    "metrics_figure",
    "pareto_figure",
    "timespace_figure",
    "trajectories_figure",
]
