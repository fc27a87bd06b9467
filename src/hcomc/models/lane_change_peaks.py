"""Re-exports :mod:`hcomc.equations.lane_change_peaks` for one release: import from there."""

from hcomc.equations.lane_change_peaks import (
    PEAK_ACCEL_FACTOR,
    PEAK_JERK_FACTOR,
    PEAK_SPEED_FACTOR,
    min_duration,
    peak_lateral_accel,
    peak_lateral_jerk,
    peak_lateral_speed,
)

__all__ = [
    "PEAK_ACCEL_FACTOR",
    "PEAK_JERK_FACTOR",
    "PEAK_SPEED_FACTOR",
    "min_duration",
    "peak_lateral_accel",
    "peak_lateral_jerk",
    "peak_lateral_speed",
]
