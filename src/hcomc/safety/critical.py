"""The Eq. 15 parameters of a configuration (:class:`SafetyIndex`); the critical acceleration
itself, paper Eq. (15), is :mod:`hcomc.equations.safety`, which this module also re-exports
(``critical_acceleration``, ``critical_accel``) for one release: import it from there."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from hcomc._typing import FloatArray
from hcomc.equations.safety import critical_accel, critical_acceleration

if TYPE_CHECKING:
    from hcomc.config import ControlParams

__all__ = ["SafetyIndex", "critical_accel", "critical_acceleration"]


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
