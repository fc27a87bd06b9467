"""Eq. 2: what a human driver perceives, with reaction delays and estimation errors.

The paper's HDVs follow the IDM (Eq. 1) on *estimated* inputs: "the gap and speed difference
are estimated by the driver with a reaction time" and with errors (paper Section II-B, Eq. 2).
hcomc takes both from the Human Driver Model (Treiber, Kesting & Helbing, Physica A 360
(2006) 71-88): a quantity at ``t - tau`` with ``tau = (j + r) dt`` is interpolated linearly
between the stored steps ``j`` and ``j + 1`` ago, and the gap and the approach rate carry
multiplicative and inverse-TTC errors driven by Ornstein-Uhlenbeck processes of variance
about 1. The engine applies them to every HDV of a step at once
(:func:`hcomc.sim.perception.perceive_into`); CAVs perceive exactly.

Reference: Wang, Wang, Pan, Jiao and Claudel, "HCOMC: A Hierarchical Cooperative On-Ramp
Merging Control Framework in Mixed Traffic Environment on Two-Lane Highways",
arXiv:2507.11621, Section II-B, Eq. (2).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from hcomc._jit import kernel

__all__ = ["ErrorScales", "perceived"]


class ErrorScales(NamedTuple):
    """Size of the HDVs' estimation errors (Eq. 2), the same for every driver of a run."""

    gap: float  # V_s [-]: the gap s is estimated as s exp(V_s w_s)
    inverse_ttc: float  # sigma_r [1/s]: the approach rate dv as dv + s sigma_r w_l
    enabled: bool  # False: exact estimates (w_s, w_l are not read)


@kernel(inline="always")
def delay_rows(step: int, tau: float, dt: float, size: int) -> tuple[int, int, float]:
    """Where ``t - tau`` lies in a ring buffer of ``size`` rows at ``step``: the rows
    ``n - j`` and ``n - j - 1`` and the weight ``r`` of the older (``tau = (j + r) dt``). The
    same for every vehicle, so a step computes it once per delay."""
    lag = tau / dt
    j = math.floor(lag + 1e-9)
    r = max(lag - j, 0.0)
    return (step - j) % size, (step - j - 1) % size, r


@kernel(inline="always")
def interpolate(now: float, older: float, r: float) -> float:
    """The state at ``(j + r) dt`` ago from the rows ``j`` and ``j + 1`` ago (linear)."""
    if r == 0.0:
        return now
    return (1.0 - r) * now + r * older


@kernel(inline="always")
def perceived(
    x_i: float, x_l: float, leader_length: float, v_i: float, dv: float, has: bool,
    w_gap: float, w_ttc: float, scales: ErrorScales,
) -> tuple[float, float, float]:  # fmt: skip
    """The inputs of a human driver's car following (paper Eq. 2): the estimated gap, own speed
    and estimated leader speed, from delayed states and with estimation errors.

    .. math::

        s_{est} = s(t - \tau_s)\\, e^{V_s w_s}, \\qquad
        \\Delta v_{est} = \\Delta v(t - \tau_{\\Delta v}) + s\\, \\sigma_r\\, w_l, \\qquad
        v_{l,est} = v(t - \tau_v) - \\Delta v_{est}

    where the paper's :math:`s_{est}` and :math:`v_{est}` are the gap and speeds the driver
    "estimates" with reaction delays :math:`\tau` and Wiener-process errors :math:`w` (Human
    Driver Model, Treiber, Kesting & Helbing 2006).

    Parameters
    ----------
    x_i, x_l : float
        Delayed front-bumper positions of the driver and of its leader [m].
    leader_length : float
        The leader's length [m]; the gap is bumper to bumper.
    v_i : float
        The driver's delayed speed [m/s].
    dv : float
        The delayed approach rate v_i - v_l [m/s].
    has : bool
        Whether a leader exists; without one the gap is infinite and dv is not read.
    w_gap, w_ttc : float
        The driver's error processes w_s and w_l [-] (variance about 1).
    scales : ErrorScales
        V_s [-] and sigma_r [1/s], and whether errors are applied at all.

    Returns
    -------
    tuple of float
        ``(s_est [m], v [m/s], v_leader_est [m/s])``.
    """
    s = x_l - leader_length - x_i if has else math.inf
    if scales.enabled:
        s_true = s if has else 0.0
        dv = dv + s_true * scales.inverse_ttc * w_ttc
        s = s * math.exp(scales.gap * w_gap)
    return s, v_i, v_i - (dv if has else 0.0)
