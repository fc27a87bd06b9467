r"""Adaptive smoothing of a binned speed field for contour maps (display only).

With the metric binning (10 m x 0.5 s) and the paper's light traffic (time headways of
3-7 s) most bins of :func:`hcomc.metrics.speed_field` are empty: a raw map shows isolated
vehicle streaks rather than a field. Contour maps therefore show the field reconstructed
with the *adaptive smoothing method* (ASM) of Treiber & Helbing (2002), the standard way
to draw speed contour maps from sparse traffic data:

.. math::

   V(x, t) = w\,V_{cong}(x, t) + (1 - w)\,V_{free}(x, t), \qquad
   w = \tfrac12\left[1 + \tanh\frac{V_c - \min(V_{free}, V_{cong})}{\Delta V}\right]

where :math:`V_{free}` and :math:`V_{cong}` are kernel-weighted means of the occupied bins
with the kernels :math:`\phi(x, t) = \exp(-|x|/\sigma - |t - x/c|/\tau)` stretched along
the characteristic speeds :math:`c = c_{free}` (perturbations travel downstream in free
flow) and :math:`c = c_{cong}` (upstream in congestion). Points far from any data (kernel
coverage below ``min_coverage``) stay NaN. The metrics (LSRV) always integrate the raw
bins; this module only serves figures and has no matplotlib dependency.

References
----------
M. Treiber and D. Helbing, "Reconstructing the spatio-temporal traffic dynamics from
stationary detector data," *Cooperative Transportation Dynamics* 1, 3.1-3.24 (2002).
M. Treiber, A. Kesting and R. E. Wilson, "Reconstructing the traffic state by fusion of
heterogeneous data," *Computer-Aided Civil and Infrastructure Engineering* 26, 408-419
(2011).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import fftconvolve

from hcomc._typing import FloatArray

__all__ = [
    "C_CONG",
    "C_FREE",
    "DV",
    "MIN_COVERAGE",
    "SIGMA",
    "TAU",
    "V_CRIT",
    "adaptive_smoothing",
]

SIGMA = 50.0
"""Spatial smoothing width sigma [m] (about one vehicle streak spacing of 150 m / 3)."""
TAU = 2.5
"""Temporal smoothing width tau [s] (half the paper's 5 s mean headway)."""
C_FREE = 80.0 / 3.6
"""Free-flow characteristic speed c_free [m/s] (80 km/h, Treiber & Helbing 2002)."""
C_CONG = -15.0 / 3.6
"""Congested characteristic speed c_cong [m/s] (-15 km/h, Treiber & Helbing 2002)."""
V_CRIT = 60.0 / 3.6
"""Crossover speed V_c between the free and congested fields [m/s] (60 km/h)."""
DV = 20.0 / 3.6
"""Width Delta V of the crossover [m/s] (20 km/h)."""
MIN_COVERAGE = 0.02
"""Smallest share of a point's kernel mass on occupied bins for a value; below: NaN [-]."""


def _kernel(
    dx: float, dt: float, sigma: float, tau: float, c: float
) -> tuple[FloatArray, FloatArray]:
    """ASM kernel on the bin grid, axes (t, x), centred on the zero offset."""
    n_x = math.ceil(4.0 * sigma / dx)
    n_t = math.ceil((4.0 * tau + 4.0 * sigma / abs(c)) / dt)
    ox = np.arange(-n_x, n_x + 1) * dx
    ot = np.arange(-n_t, n_t + 1) * dt
    T, X = np.meshgrid(ot, ox, indexing="ij")
    return np.exp(-np.abs(X) / sigma - np.abs(T - X / c) / tau), ox.astype(np.float64, copy=False)


def _weighted_mean(
    values: FloatArray, occupied: FloatArray, kernel: FloatArray
) -> tuple[FloatArray, FloatArray]:
    num = fftconvolve(values, kernel, mode="same")
    den = fftconvolve(occupied, kernel, mode="same")
    full = fftconvolve(np.ones_like(occupied), kernel, mode="same")
    tiny = 1e-12 * float(kernel.sum())
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(den > tiny, num / np.maximum(den, tiny), np.nan)
        coverage = np.where(full > tiny, den / np.maximum(full, tiny), 0.0)
    return mean, coverage


def adaptive_smoothing(
    x_edges: FloatArray,
    t_edges: FloatArray,
    V: FloatArray,
    *,
    sigma: float = SIGMA,
    tau: float = TAU,
    c_free: float = C_FREE,
    c_cong: float = C_CONG,
    v_crit: float = V_CRIT,
    dv: float = DV,
    min_coverage: float = MIN_COVERAGE,
) -> FloatArray:
    """Adaptive-smoothing reconstruction of a binned speed field (module docstring).

    Parameters
    ----------
    x_edges : numpy.ndarray, shape (n_x + 1,)
        Space bin edges [m] (uniform spacing assumed; a narrower last bin is ignored).
    t_edges : numpy.ndarray, shape (n_t + 1,)
        Time bin edges [s].
    V : numpy.ndarray, shape (n_t, n_x)
        Mean speed per bin [m/s], NaN for empty bins (as from
        :func:`hcomc.metrics.speed_field`).
    sigma, tau : float
        Kernel widths in space [m] and time [s] (> 0).
    c_free, c_cong : float
        Characteristic speeds of free and congested traffic [m/s] (non-zero).
    v_crit, dv : float
        Crossover speed and its width [m/s] (dv > 0).
    min_coverage : float
        Points whose kernel mass on occupied bins is below this share get NaN.

    Returns
    -------
    numpy.ndarray, shape (n_t, n_x)
        Smoothed speed [m/s]; NaN far from any occupied bin. An all-empty field stays
        all NaN.

    Raises
    ------
    ValueError
        On non-positive widths or zero characteristic speeds, or mismatched shapes.
    """
    V = np.asarray(V, dtype=np.float64)
    x_edges = np.asarray(x_edges, dtype=np.float64)
    t_edges = np.asarray(t_edges, dtype=np.float64)
    if V.shape != (t_edges.size - 1, x_edges.size - 1):
        raise ValueError(
            f"V has shape {V.shape}, expected (len(t_edges) - 1, len(x_edges) - 1) = "
            f"{(t_edges.size - 1, x_edges.size - 1)}"
        )
    if not (sigma > 0 and tau > 0 and dv > 0 and c_free != 0 and c_cong != 0):
        raise ValueError(
            f"need sigma, tau, dv > 0 and non-zero c_free, c_cong; got sigma={sigma}, "
            f"tau={tau}, dv={dv}, c_free={c_free}, c_cong={c_cong}"
        )
    occupied = np.isfinite(V)
    if not occupied.any() or V.size == 0:
        return np.full(V.shape, np.nan)
    dx = float(x_edges[1] - x_edges[0])
    dt = float(t_edges[1] - t_edges[0])
    values = np.where(occupied, V, 0.0)
    occ = occupied.astype(np.float64)
    k_free, _ = _kernel(dx, dt, sigma, tau, c_free)
    k_cong, _ = _kernel(dx, dt, sigma, tau, c_cong)
    v_free, cov = _weighted_mean(values, occ, k_free)
    v_cong, _ = _weighted_mean(values, occ, k_cong)
    v_cong = np.where(np.isfinite(v_cong), v_cong, v_free)
    w = 0.5 * (1.0 + np.tanh((v_crit - np.fmin(v_free, v_cong)) / dv))
    out = w * v_cong + (1.0 - w) * v_free
    out[cov < min_coverage] = np.nan
    return out
