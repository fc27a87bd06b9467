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

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import HDVParams


@kernel(inline="always")
def delayed(hist: np.ndarray, step: int, col: int, tau: float, dt: float) -> float:
    """Column ``col`` of the ring buffer ``hist`` at ``t - tau`` (linear interpolation)."""
    size = hist.shape[0]
    lag = tau / dt
    j = math.floor(lag + 1e-9)
    r = max(lag - j, 0.0)
    now = hist[(step - j) % size, col]
    if r == 0.0:
        return now
    return (1.0 - r) * now + r * hist[(step - j - 1) % size, col]


@kernel(inline="always")
def perceive_one(
    x_hist: np.ndarray, v_hist: np.ndarray, w_gap: np.ndarray, w_ttc: np.ndarray,
    step: int, i: int, leader: int, leader_length: float, dt: float, taus: np.ndarray,
    gap_error: float, ttc_error: float, errors: bool,
) -> tuple[float, float, float]:  # fmt: skip
    """Delayed, noisy ``(s_est, v, v_leader_est)`` of HDV i behind ``leader`` (-1: none; the
    gap is then infinite). ``taus`` = reaction times on gap, own speed and approach rate [s]."""
    has = leader >= 0
    lead = leader if has else i
    x_i = delayed(x_hist, step, i, taus[0], dt)
    x_l = delayed(x_hist, step, lead, taus[0], dt)
    s = x_l - leader_length - x_i if has else math.inf
    v = delayed(v_hist, step, i, taus[1], dt)
    dv = delayed(v_hist, step, i, taus[2], dt) - delayed(v_hist, step, lead, taus[2], dt)
    if errors:
        s_true = s if has else 0.0
        dv = dv + s_true * ttc_error * w_ttc[i]
        s = s * math.exp(gap_error * w_gap[i])
    return s, v, v - (dv if has else 0.0)


@kernel
def advance_errors_of(
    w_gap: np.ndarray, w_ttc: np.ndarray, ids: np.ndarray, xi: np.ndarray, decay: float,
    kick: float,
) -> None:  # fmt: skip
    """One OU step of both error processes for vehicles ``ids`` with innovations ``xi`` (2, N)."""
    for i in ids:
        w_gap[i] = decay * w_gap[i] + kick * xi[0, i]
        w_ttc[i] = decay * w_ttc[i] + kick * xi[1, i]


@kernel
def _perceive_many(x_hist, v_hist, w_gap, w_ttc, step, ids, leader, length, dt, taus, ge, te, err):
    s, v, vl = np.empty(ids.size), np.empty(ids.size), np.empty(ids.size)
    for k in range(ids.size):
        s[k], v[k], vl[k] = perceive_one(
            x_hist, v_hist, w_gap, w_ttc, step, ids[k], leader[k], length[k], dt, taus, ge, te, err
        )
    return s, v, vl


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
        advance_errors_of(self.w_gap, self.w_ttc, _ints(ids), xi, self.decay, self.kick)

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
        return _perceive_many(
            self.x_hist, self.v_hist, self.w_gap, self.w_ttc, step, _ints(ids), _ints(leader),
            np.ascontiguousarray(leader_length, dtype=np.float64), self.dt, self.taus,
            p.gap_error, p.inverse_ttc_error, self.errors,
        )  # fmt: skip


def _ints(a: IntArray) -> IntArray:
    return np.ascontiguousarray(a, dtype=np.int64).reshape(-1)
