"""A corridor's road as the arrays the compiled corridor step reads.

Every lane a vehicle can drive in has a *code*: mainline lane k (counted from the right,
0 = rightmost) is code k; lane j of ramp r (j = 0 next to the mainline, r in the order of
:attr:`hcomc.corridor.Road.ramps`: on-ramps, then off-ramps, each by x) is code
``M + 2 r + j``, with M the largest mainline lane count. A ramp's code covers the ramp road
and its acceleration or deceleration lanes: an on-ramp's from ``x - ramp_length`` to the end
of its acceleration lanes, where it ends; an off-ramp's from ``x`` to the end of its ramp road,
``x + decel_length + ramp_length``, where its vehicles arrive. Lanes exist where the
sections of :func:`hcomc.corridor.sections` say, the one description the SUMO export reads
too; :func:`hcomc.sim.corridor.setup.build_layout` builds the arrays from them, with the codes
of :mod:`hcomc.corridor.layout` (which also places them in the plane for the views of a run).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["KIND_MAIN", "KIND_OFF", "KIND_ON", "Layout"]

KIND_MAIN, KIND_ON, KIND_OFF = 0, 1, 2
"""Kinds of a code (and of a section: mainline only, acceleration or deceleration lanes)."""


class Layout(NamedTuple):
    """The road's arrays (module docstring). Sections s: ``sec_*``; codes c: ``code_*``.
    Arrays only, so that a kernel can borrow them all (:data:`hcomc._jit.borrow_all`)."""

    sec_x0: np.ndarray  # section start [m]
    sec_x1: np.ndarray  # section end [m]
    sec_lanes: np.ndarray  # mainline lanes
    sec_ramp: np.ndarray  # code of the ramp lane next to the mainline (j = 0), -1 if none
    sec_kind: np.ndarray  # KIND_MAIN, KIND_ON (acceleration lanes), KIND_OFF (deceleration)
    sec_speed: np.ndarray  # speed limit [m/s]
    lane_end: np.ndarray  # (M, S): where mainline lane k ends at or after section s [m], inf
    code_kind: np.ndarray  # KIND_* of each code
    code_x0: np.ndarray  # ramp codes: where the junction with the mainline starts [m]
    code_x1: np.ndarray  # ramp codes: where it ends (end of the acceleration/deceleration lane)
    code_far: np.ndarray  # on-ramp: start of the ramp road; off-ramp: where vehicles arrive
    code_speed: np.ndarray  # ramp codes: speed limit of the ramp road [m/s]
    code_left: np.ndarray  # ramp codes: the code to the left (main lane 0 for j = 0)
    code_right: np.ndarray  # ramp codes: the code to the right, -1 if none

    @property
    def n_main(self) -> int:
        """M, the largest mainline lane count (in a kernel: ``lane_end.shape[0]``)."""
        return int(self.lane_end.shape[0])

    @property
    def length(self) -> float:
        """Mainline length [m] (in a kernel: ``sec_x1[-1]``)."""
        return float(self.sec_x1[-1])

    @property
    def n_codes(self) -> int:
        """Number of lane codes."""
        return int(self.code_kind.size)
