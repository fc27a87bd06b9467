"""The fuel model's coefficients as configuration: a validated, frozen model of the
coefficients of paper Eq. (16) (:mod:`hcomc.equations.fuel`, whose kernels take them as a
:class:`~hcomc.equations.fuel.FuelCoefficients`)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from hcomc.equations.fuel import DEFAULT_COEFFICIENTS

__all__ = ["FUEL_DEFAULT", "FuelParams"]

_K = DEFAULT_COEFFICIENTS


class FuelParams(BaseModel):
    """Coefficients of the Eq. (16) fuel-rate polynomial (Kamal et al. 2011).

    Defaults: Q and R of Kamal et al. (2011) as used by Rios-Torres & Malikopoulos (2017)
    (``SEUChang/CBF_Merging`` ``fuel_consumption.m``), those of
    :data:`hcomc.equations.fuel.DEFAULT_COEFFICIENTS`.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    cruise: tuple[float, float, float, float] = Field(
        default=(_K.b0, _K.b1, _K.b2, _K.b3),
        description=(
            "Q = (b0, b1, b2, b3) of the cruise rate b0 + b1 v + b2 v^2 + b3 v^3, units "
            "[mL/s], [mL/m], [mL s/m^2], [mL s^2/m^3] (v in m/s)."
        ),
    )
    accel: tuple[float, float, float] = Field(
        default=(_K.c0, _K.c1, _K.c2),
        description=(
            "R = (c0, c1, c2) of the acceleration rate a (c0 + c1 v + c2 v^2), units "
            "[mL s/m], [mL s^2/m^2], [mL s^3/m^3] (v in m/s, a in m/s^2)."
        ),
    )
    accel_term: Literal["positive", "signed"] = Field(
        default="positive",
        description=(
            "'positive': acceleration term for a > 0 only, no fuel credit for braking "
            "(default); 'signed': term applied for any sign of a. The total rate "
            "[mL/s] is clipped at 0 in both cases."
        ),
    )

    def coefficients(self) -> tuple[float, ...]:
        """``(b0, b1, b2, b3, c0, c1, c2, positive_only)``: the fields of
        :class:`~hcomc.equations.fuel.FuelCoefficients`, the kernels' arguments after ``v``
        and ``a``."""
        positive = 1.0 if self.accel_term == "positive" else 0.0
        return (*self.cruise, *self.accel, positive)


FUEL_DEFAULT = FuelParams()
"""Default :class:`FuelParams`: Kamal et al. (2011) coefficients, no credit for braking."""
