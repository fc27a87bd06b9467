"""Road layout: lane indices, lateral geometry and the key-vehicle roles of a merge.

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

KEY_ROLES: tuple[str, ...] = ("VR", "VMC", "VMF", "VMR", "VNF", "VNR")
"""The six key vehicles of a merge (paper Section II-A, Fig. 1): the ramp vehicle VR, the
main-lane-1 vehicle VMC it cooperates with, the leader VMF and follower VMR of the gap in
lane 1, and the leader VNF and follower VNR of VMC's gap in lane 2. Every per-role array,
dict and plan record uses this order."""

VR, VMC, VMF, VMR, VNF, VNR = range(len(KEY_ROLES))
"""Index of each key role in every per-role array (the order of :data:`KEY_ROLES`)."""
N_ROLES = len(KEY_ROLES)


def lane_centre(lane: IntArray | int, width: float) -> FloatArray:
    """Lateral position y of a lane's centre line [m]."""
    return (np.asarray(lane, dtype=np.float64) - 1.0) * width
