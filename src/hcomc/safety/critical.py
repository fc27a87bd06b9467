"""Critical acceleration, the HCOMC safety index (paper Eq. 15)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.models._broadcast import broadcast_apply

if TYPE_CHECKING:
    from hcomc.config import ControlParams


def critical_acceleration(
    d: ArrayLike,
    v_r: ArrayLike,
    v_f: ArrayLike,
    *,
    delay: ArrayLike,
    min_distance: float,
    emergency_decel: float,
) -> FloatArray:
    r"""Deceleration the rear vehicle needs if its leader brakes in an emergency [m/s^2].

    .. math::
       :label: eq-15-critical-acceleration

       U_{safe} = a_{cr} = \frac{v_r^2}{2\left(d_{cri} - D - v_r T
                  + \frac{v_f^2}{2 a_{merg}}\right)}

    The leader brakes from ``v_f`` at ``a_merg``; the follower reacts after ``T`` and then
    brakes at constant ``a_cr``, stopping ``D`` behind it. A denominator ``<= 0`` means no
    deceleration avoids the crash: the result is ``+inf`` (infeasible).

    Parameters
    ----------
    d : bumper-to-bumper gap d_cri [m].
    v_r, v_f : rear (follower) and front (leader) speed [m/s].
    delay : reaction plus brake build-up T [s] (0.5 CAV, 1.0 HDV follower).
    min_distance : residual distance D [m].
    emergency_decel : leader's emergency deceleration a_merg [m/s^2].

    Examples
    --------
    >>> round(float(critical_acceleration(50.0, 25.0, 25.0, delay=1.0, min_distance=2.0,
    ...                                   emergency_decel=7.5)), 2)
    4.83
    """
    return broadcast_apply(
        _critical_array, d, v_r, v_f, delay, float(min_distance), float(emergency_decel)
    )


@kernel
def critical_accel(
    d: float, v_r: float, v_f: float, delay: float, min_distance: float, emergency_decel: float
) -> float:
    """Eq. 15 for one follower-leader pair [m/s^2] (``inf`` when no deceleration avoids the
    crash): the one implementation behind :func:`critical_acceleration` (same arguments,
    positional)."""
    denom = 2.0 * (d - min_distance - v_r * delay + v_f * v_f / (2.0 * emergency_decel))
    return v_r * v_r / denom if denom > 0.0 else np.inf


@kernel
def _critical_array(
    d: np.ndarray, v_r: np.ndarray, v_f: np.ndarray, delay: np.ndarray,
    min_distance: np.ndarray, emergency_decel: np.ndarray,
) -> np.ndarray:  # fmt: skip
    out = np.empty(d.size)
    for i in range(d.size):
        out[i] = critical_accel(d[i], v_r[i], v_f[i], delay[i], min_distance[i], emergency_decel[i])
    return out


@dataclass(frozen=True, slots=True)
class SafetyIndex:
    """The Eq. 15 parameters and the Eq. 19 threshold, read once from ``config.control``.

    Every consumer (the HCOMC prediction, PSO/SA scoring, the lane-change and merge games,
    figures) takes them from here, so a config change reaches all of them.
    """

    delay_cav: float
    delay_hdv: float
    min_distance: float
    emergency_decel: float
    threshold: float

    @classmethod
    def from_config(cls, control: ControlParams) -> SafetyIndex:
        """The values of ``control.safety_*``."""
        return cls(
            delay_cav=control.safety_delay_cav,
            delay_hdv=control.safety_delay_hdv,
            min_distance=control.safety_min_distance,
            emergency_decel=control.safety_emergency_decel,
            threshold=control.safety_threshold,
        )

    def delay(self, follower_is_cav: ArrayLike) -> FloatArray:
        """Eq. 15 delay T of each follower [s]."""
        return np.where(np.asarray(follower_is_cav, dtype=bool), self.delay_cav, self.delay_hdv)

    def __call__(
        self, d: ArrayLike, v_r: ArrayLike, v_f: ArrayLike, follower_is_cav: ArrayLike
    ) -> FloatArray:
        """:func:`critical_acceleration` with these parameters [m/s^2]."""
        return critical_acceleration(
            d,
            v_r,
            v_f,
            delay=self.delay(follower_is_cav),
            min_distance=self.min_distance,
            emergency_decel=self.emergency_decel,
        )
