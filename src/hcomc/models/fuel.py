"""Re-exports :mod:`hcomc.equations.fuel` (paper Eq. 16) and the configuration's
:class:`~hcomc.config.fuel.FuelParams`, for one release: import from there."""

from hcomc.config.fuel import FUEL_DEFAULT, FuelParams
from hcomc.equations.fuel import FuelCoefficients, fuel_consumed, fuel_rate, fuel_rate_scalar

__all__ = [
    "FUEL_DEFAULT",
    "FuelCoefficients",
    "FuelParams",
    "fuel_consumed",
    "fuel_rate",
    "fuel_rate_scalar",
]
