"""What drivers perceive: exact for CAVs, delayed and noisy for HDVs (paper Eq. 2).

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
* **Independent of who is on the road**: every step draws the innovations ``xi`` for *all* N
  vehicles of the run (column i always belongs to vehicle i) and applies them to the active
  HDVs only. A vehicle's error path therefore depends on the seed and on the steps it is
  active, never on which other vehicles exist, so a run without the ramp vehicle (the
  undisturbed counterfactual) gives bit-identical trajectories to every vehicle the merge
  does not touch. (The engine advances the errors on every step with at least one active
  vehicle.)

A vehicle's buffer column is filled with its release state, so before K steps of history
exist the current values are used.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import HDVParams


class History(NamedTuple):
    """The ring buffers of past states that the reaction delays read, and the delays."""

    x: np.ndarray  # (K, N) positions [m]; step n in row n % K
    v: np.ndarray  # (K, N) speeds [m/s]
    taus: np.ndarray  # (3,) reaction times on gap, own speed and approach rate [s]
    dt: float  # time step [s]


class ErrorScales(NamedTuple):
    """Size of the HDVs' estimation errors (Eq. 2), the same for every driver of a run."""

    gap: float  # V_s [-]: the gap s is estimated as s exp(V_s w_s)
    inverse_ttc: float  # sigma_r [1/s]: the approach rate dv as dv + s sigma_r w_l
    enabled: bool  # False: exact estimates (w_s, w_l are not read)


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
def perception_rows(
    step: int, taus: np.ndarray, dt: float, size: int
) -> tuple[tuple[int, int, float], tuple[int, int, float], tuple[int, int, float]]:
    """:func:`delay_rows` of the three reaction times ``taus`` (gap, speed, approach rate)."""
    return (
        delay_rows(step, taus[0], dt, size),
        delay_rows(step, taus[1], dt, size),
        delay_rows(step, taus[2], dt, size),
    )


@kernel(inline="always")
def perceived(
    x_i: float, x_l: float, leader_length: float, v_i: float, dv: float, has: bool,
    w_gap: float, w_ttc: float, scales: ErrorScales,
) -> tuple[float, float, float]:  # fmt: skip
    """Eq. 2: ``(s_est, v, v_leader_est)`` from the delayed positions ``x_i``, ``x_l``, the
    delayed speed ``v_i`` and the delayed approach rate ``dv`` (``has``: a leader exists, else
    the gap is infinite), with the driver's estimation errors ``w_gap``, ``w_ttc`` when
    ``scales.enabled``."""
    s = x_l - leader_length - x_i if has else math.inf
    if scales.enabled:
        s_true = s if has else 0.0
        dv = dv + s_true * scales.inverse_ttc * w_ttc
        s = s * math.exp(scales.gap * w_gap)
    return s, v_i, v_i - (dv if has else 0.0)


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


class Perception:
    """Ring buffer of past states plus the HDVs' estimation-error processes."""

    def __init__(
        self, params: HDVParams, is_hdv: BoolArray, dt: float, rng: np.random.Generator
    ) -> None:
        n = is_hdv.size
        self.dt = dt
        self.params = params
        self.is_hdv = is_hdv
        lags = [
            params.reaction_time_gap,
            params.reaction_time_speed,
            params.reaction_time_approach,
        ]
        self.size = int(np.floor(max(lags) / dt + 1e-9)) + 2
        self.x_hist = np.zeros((self.size, n))
        self.v_hist = np.zeros((self.size, n))
        self.errors = params.estimation_errors and (
            params.gap_error > 0 or params.inverse_ttc_error > 0
        )
        self.w_gap = rng.standard_normal(n) if self.errors else np.zeros(n)
        self.w_ttc = rng.standard_normal(n) if self.errors else np.zeros(n)
        self.decay = np.exp(-dt / params.error_correlation_time)
        self.kick = np.sqrt(2.0 * dt / params.error_correlation_time)

    def fill(self, ids: IntArray, x: FloatArray, v: FloatArray) -> None:
        """Initialise the history of newly released vehicles with their current state."""
        self.x_hist[:, ids] = x[ids]
        self.v_hist[:, ids] = v[ids]

    def push(self, step: int, x: FloatArray, v: FloatArray) -> None:
        """Store the state at ``step`` (all vehicles)."""
        row = step % self.size
        self.x_hist[row] = x
        self.v_hist[row] = v

    def advance_errors(self, ids: IntArray, rng: np.random.Generator) -> None:
        """One OU step of both error processes for the active HDVs ``ids``.

        Innovations are drawn for all N vehicles (even when ``ids`` is empty) so the random
        stream does not depend on which vehicles are active.
        """
        if not self.errors:
            return
        xi = rng.standard_normal((2, self.is_hdv.size))
        advance_errors_of(
            self.w_gap, self.w_ttc, _ints(ids), self.is_hdv, xi, self.decay, self.kick
        )

    @property
    def taus(self) -> FloatArray:
        """Reaction times on gap, own speed and approach rate [s]."""
        p = self.params
        return np.array(
            [p.reaction_time_gap, p.reaction_time_speed, p.reaction_time_approach], dtype=float
        )

    def perceive(
        self, step: int, ids: IntArray, leader: IntArray, leader_length: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Delayed, noisy ``(s_est, v, v_leader_est)`` of HDVs ``ids`` behind ``leader``.

        ``leader`` is -1 where there is none: the gap is then infinite.
        """
        p = self.params
        ids, leader = _ints(ids), _ints(leader)
        s, v, vl = np.empty(ids.size), np.empty(ids.size), np.empty(ids.size)
        scales = ErrorScales(p.gap_error, p.inverse_ttc_error, self.errors)
        perceive_into(
            History(self.x_hist, self.v_hist, self.taus, self.dt), step,
            EstimationErrors(self.w_gap, self.w_ttc, scales), ids, leader,
            np.ascontiguousarray(leader_length, dtype=np.float64),
            np.ones(self.is_hdv.size, dtype=np.bool_), Estimates(s, v, vl),
        )  # fmt: skip
        return s, v, vl


def _ints(a: IntArray) -> IntArray:
    return np.ascontiguousarray(a, dtype=np.int64).reshape(-1)
