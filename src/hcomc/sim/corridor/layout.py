"""A corridor's road as the arrays the compiled corridor step reads.

Every lane a vehicle can drive in has a *code*: mainline lane k (counted from the right,
0 = rightmost) is code k; lane j of ramp r (j = 0 next to the mainline, r in the order of
:attr:`hcomc.corridor.Road.ramps`: on-ramps, then off-ramps, each by x) is code
``M + 2 r + j``, with M the largest mainline lane count. A ramp's code covers the ramp road
and its acceleration or deceleration lanes: an on-ramp's from ``x - ramp_length`` to the end
of its acceleration lanes, where it ends; an off-ramp's from ``x`` to the end of its ramp road,
``x + decel_length + ramp_length``, where its vehicles arrive. Lanes exist where the
sections of :func:`hcomc.corridor.sections` say, the one description the SUMO export reads
too.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hcomc.corridor import Corridor, OnRamp, sections

__all__ = ["KIND_MAIN", "KIND_OFF", "KIND_ON", "Layout", "build_layout"]

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

    def ramp_code(self, ramp_id: str, c: Corridor) -> int:
        """Code of lane j = 0 of ramp ``ramp_id``."""
        ids = [r.id for r in c.road.ramps]
        return self.n_main + 2 * ids.index(ramp_id)


def build_layout(c: Corridor) -> Layout:
    """The :class:`Layout` of corridor ``c``."""
    road, secs = c.road, sections(c.road)
    n_main = max(s.lanes for s in secs)
    n_codes = n_main + 2 * len(road.ramps)
    base = {r.id: n_main + 2 * k for k, r in enumerate(road.ramps)}
    kinds = {"main": KIND_MAIN, "accel": KIND_ON, "decel": KIND_OFF}
    sec_lanes = np.array([s.lanes for s in secs], dtype=np.int64)
    lane_end = np.full((n_main, len(secs)), np.inf)
    for k in range(n_main):
        end = np.inf
        for s in range(len(secs) - 1, -1, -1):  # from downstream: the next section without k
            if sec_lanes[s] <= k:
                end = secs[s].x0
            lane_end[k, s] = end
    code_kind = np.zeros(n_codes, dtype=np.int64)
    code_x0, code_x1, code_far, code_speed = (np.zeros(n_codes) for _ in range(4))
    code_left = np.full(n_codes, -1, dtype=np.int64)
    code_right = np.full(n_codes, -1, dtype=np.int64)
    for ramp in road.ramps:
        on = isinstance(ramp, OnRamp)
        for j in range(2):
            code = base[ramp.id] + j
            code_kind[code] = KIND_ON if on else KIND_OFF
            code_x0[code], code_x1[code] = ramp.x, ramp.end
            code_far[code] = ramp.x - ramp.ramp_length if on else ramp.end + ramp.ramp_length
            code_speed[code] = road.speed_at(ramp.x)
            code_left[code] = 0 if j == 0 else code - 1
            code_right[code] = code + 1 if j + 1 < ramp.lanes else -1
    return Layout(
        sec_x0=np.array([s.x0 for s in secs]),
        sec_x1=np.array([s.x1 for s in secs]),
        sec_lanes=sec_lanes,
        sec_ramp=np.array([base[s.ramp] if s.ramp else -1 for s in secs], dtype=np.int64),
        sec_kind=np.array([kinds[s.kind] for s in secs], dtype=np.int64),
        sec_speed=np.array([s.speed_limit for s in secs]),
        lane_end=lane_end,
        code_kind=code_kind,
        code_x0=code_x0,
        code_x1=code_x1,
        code_far=code_far,
        code_speed=code_speed,
        code_left=code_left,
        code_right=code_right,
    )
