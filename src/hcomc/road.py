"""Road layout: lane indices and lateral geometry (DESIGN.md §3).

Lanes are numbered so that ``lane - 1`` is the lateral offset in lane widths: the ramp and
acceleration lane (``RAMP = 0``) at y = -W, lane 1 (right, ``MAIN_1 = 1``) at y = 0 and lane 2
(outer, ``MAIN_2 = 2``) at y = +W.
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np

from hcomc._typing import FloatArray, IntArray


class Lane(IntEnum):
    """Lane index; ``lane - 1`` is the lateral offset in lane widths."""

    RAMP = 0
    MAIN_1 = 1
    MAIN_2 = 2


class Kind(IntEnum):
    """Vehicle kind."""

    HDV = 0
    CAV = 1


N_LANES = 3


def lane_centre(lane: IntArray | int, width: float) -> FloatArray:
    """Lateral position y of a lane's centre line [m]."""
    return (np.asarray(lane, dtype=np.float64) - 1.0) * width
