"""Per-vehicle model parameters as arrays, and the car-following dispatch (Eq. 1-3).

The engine gathers each vehicle's parameters from its kind's frozen parameter model into
``(N,)`` arrays once, so kernels run vectorised over heterogeneous vehicles. HDVs and CAVs
share one code path: an HDV is an ACC vehicle with coolness c = 0, which makes Eq. 3 collapse
to the IDM (its human factors live in :mod:`hcomc.sim.perception`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import ScenarioConfig
from hcomc.equations.car_following import follow_acceleration
from hcomc.road import Kind


@dataclass(frozen=True, slots=True)
class Fleet:
    """Constant per-vehicle parameters, shape (N,) each; symbols as in Eq. 1-3."""

    kind: IntArray
    matrix: FloatArray  # (7, N): v0, T, s0, a, b, delta, coolness — one gather per call
    iidm: BoolArray
    lc_duration: FloatArray
    length: FloatArray
    width: FloatArray
    scripted: BoolArray

    # the Eq. 1-3 parameters, by symbol: rows (views) of ``matrix``
    v0 = property(lambda self: self.matrix[0], doc="desired speed v0 [m/s]")
    T = property(lambda self: self.matrix[1], doc="time headway T [s]")
    s0 = property(lambda self: self.matrix[2], doc="jam distance s0 [m]")
    a = property(lambda self: self.matrix[3], doc="maximum acceleration a [m/s^2]")
    b = property(lambda self: self.matrix[4], doc="comfortable deceleration b [m/s^2]")
    delta = property(lambda self: self.matrix[5], doc="acceleration exponent delta [-]")
    coolness = property(lambda self: self.matrix[6], doc="coolness c (0 for HDVs) [-]")

    @classmethod
    def build(cls, config: ScenarioConfig, kind: IntArray, scripted: BoolArray) -> Fleet:
        """Gather the HDV/CAV parameter models of ``config`` by ``kind``."""
        hdv, cav = config.hdv, config.cav
        is_cav = kind == Kind.CAV

        def pick(field: str) -> FloatArray:
            return np.where(is_cav, float(getattr(cav, field)), float(getattr(hdv, field)))

        n = kind.size
        fields = ("desired_speed", "time_headway", "min_gap", "max_accel", "comfort_decel",
                  "exponent")  # fmt: skip
        matrix = np.vstack([*(pick(f) for f in fields), np.where(is_cav, cav.coolness, 0.0)])
        return cls(
            kind=kind,
            matrix=matrix,
            iidm=np.where(is_cav, cav.variant == "iidm", hdv.variant == "iidm"),
            lc_duration=pick("lane_change_duration"),
            length=np.full(n, config.road.vehicle_length),
            width=np.full(n, config.road.vehicle_width),
            scripted=scripted,
        )

    @property
    def any_iidm(self) -> bool:
        """Whether any vehicle uses the improved IDM."""
        return bool(self.iidm.any())


def follow(
    fleet: Fleet, ids: IntArray, s: FloatArray, v: FloatArray, vl: FloatArray, al: FloatArray
) -> FloatArray:
    """Car-following acceleration of vehicles ``ids`` [m/s^2] (Eq. 1 for HDVs, Eq. 3 for CAVs).

    Parameters
    ----------
    s : bumper-to-bumper gap to the leader [m], ``inf`` without a leader.
    v, vl : own and leader speed [m/s].
    al : leader acceleration [m/s^2] (used by the CAH of CAVs only).
    """
    v0, T, s0, a, b, delta, c = fleet.matrix[:, ids]
    return follow_acceleration(
        s, v, vl, al, v0=v0, T=T, s0=s0, a=a, b=b, delta=delta, c=c, iidm=fleet.iidm[ids]
    )
