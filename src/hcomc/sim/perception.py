"""What drivers perceive: exact for CAVs, delayed and noisy for HDVs (paper Eq. 2), for every
vehicle of a step at once; Eq. 2 itself is :func:`hcomc.equations.perception.perceived`.

HDVs follow the Human Driver Model (Treiber, Kesting & Helbing 2006):

* **Reaction delays** tau_s, tau_v, tau_dv on gap, own speed and approach rate. Positions and
  speeds of all vehicles are kept in a ring buffer of K steps; a quantity at ``t - tau`` with
  ``tau = (j + r) dt`` is ``(1 - r) z[n - j] + r z[n - j - 1]`` (linear interpolation).
  Gaps and approach rates are formed from the delayed states of the vehicle and of its
  *current* leader (documented simplification: a new leader after a cut-in is perceived at its
  delayed position, not with the delay of noticing it).
* **Estimation errors** as Ornstein-Uhlenbeck processes ``w(t+dt) = exp(-dt/tau~) w(t) +
  sqrt(2 dt/tau~) xi`` (stationary variance ~1), independent per driver
  for the gap (``s_est = s exp(V_s w_s)``) and the inverse TTC
  (``dv_est = dv + s sigma_r w_l``); ``w(0) ~ N(0, 1)``.
* **Independent of who is on the road**: every step draws the innovations ``xi`` for every
  vehicle due by that step's time (released or not yet on the road; column i always belongs
  to vehicle i, in release order) and applies them to the active HDVs only. A vehicle's error
  path therefore depends on the seed and on the steps it is active, never on which other
  vehicles are on the road, so a run without the ramp vehicle (the undisturbed
  counterfactual) gives bit-identical trajectories to every vehicle the merge does not touch,
  and a shorter run of a seed is a prefix of a longer one (the engine advances the stream on
  every step).

A vehicle's buffer column is filled with its release state, so before K steps of history
exist the current values are used. The run's buffers and error processes are built from its
configuration by :class:`hcomc.sim.perception_state.Perception`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc.equations.perception import ErrorScales, delay_rows, interpolate, perceived


class History(NamedTuple):
    """The ring buffers of past states that the reaction delays read, and the delays."""

    x: np.ndarray  # (K, N) positions [m]; step n in row n % K
    v: np.ndarray  # (K, N) speeds [m/s]
    taus: np.ndarray  # (3,) reaction times on gap, own speed and approach rate [s]
    dt: float  # time step [s]


class EstimationErrors(NamedTuple):
    """The HDVs' estimation errors (Eq. 2): each driver's two error processes, their scales."""

    w_gap: np.ndarray  # (N,) w_s of each driver [-] (Ornstein-Uhlenbeck, variance ~1)
    w_ttc: np.ndarray  # (N,) w_l of each driver [-]
    scales: ErrorScales


class Estimates(NamedTuple):
    """What drivers perceive, each (n,) in the order of the vehicles asked about."""

    gap: np.ndarray  # estimated gap to the leader s_est [m] (inf: no leader)
    speed: np.ndarray  # own (delayed) speed v [m/s]
    leader_speed: np.ndarray  # estimated leader speed v_leader_est [m/s]


@kernel(inline="always")
def perception_rows(
    step: int, taus: np.ndarray, dt: float, size: int
) -> tuple[tuple[int, int, float], tuple[int, int, float], tuple[int, int, float]]:
    """:func:`delay_rows` of the three reaction times ``taus`` (gap, speed, approach rate)."""
    return (
        delay_rows(step, taus[0], dt, size),
        delay_rows(step, taus[1], dt, size),
        delay_rows(step, taus[2], dt, size),
    )


@kernel
def perceive_into(
    history: History, step: int, errors: EstimationErrors, ids: np.ndarray,
    leaders: np.ndarray, leader_length: np.ndarray, only: np.ndarray, out: Estimates,
) -> None:  # fmt: skip
    """Delayed (``history`` at ``step``), noisy (``errors``) ``(s_est, v, v_leader_est)`` of
    each vehicle ``ids[k]`` with ``only[ids[k]]`` behind ``leaders[k]`` (-1: none) of length
    ``leader_length[k]``, written into entry k of ``out``; the other entries are left as
    they are.

    The per-vehicle helpers take numbers, not arrays: a compiled call with array arguments
    inside the loop costs reference counting on every vehicle."""
    x_hist, v_hist, taus, dt = history
    w_gap, w_ttc, scales = errors
    s, v, vl = out
    (n0, p0, r0), (n1, p1, r1), (n2, p2, r2) = perception_rows(step, taus, dt, x_hist.shape[0])
    for k in range(ids.size):
        i, j = ids[k], leaders[k]
        if not only[i]:
            continue
        has = j >= 0
        lead = j if has else i
        x_i = interpolate(x_hist[n0, i], x_hist[p0, i], r0)
        x_l = interpolate(x_hist[n0, lead], x_hist[p0, lead], r0)
        v_i = interpolate(v_hist[n1, i], v_hist[p1, i], r1)
        dv = interpolate(v_hist[n2, i], v_hist[p2, i], r2) - interpolate(
            v_hist[n2, lead], v_hist[p2, lead], r2
        )
        s[k], v[k], vl[k] = perceived(
            x_i, x_l, leader_length[k], v_i, dv, has, w_gap[i], w_ttc[i], scales
        )


@kernel
def advance_errors_of(
    w_gap: np.ndarray, w_ttc: np.ndarray, ids: np.ndarray, is_hdv: np.ndarray, xi: np.ndarray,
    decay: float, kick: float,
) -> None:  # fmt: skip
    """One OU step of both error processes for the HDVs among vehicles ``ids`` (``is_hdv``:
    (N,) mask) with innovations ``xi`` (2, N)."""
    for i in ids:
        if is_hdv[i]:
            w_gap[i] = decay * w_gap[i] + kick * xi[0, i]
            w_ttc[i] = decay * w_ttc[i] + kick * xi[1, i]
