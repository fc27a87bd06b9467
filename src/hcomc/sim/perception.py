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

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import HDVParams


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
        self._decay = np.exp(-dt / params.error_correlation_time)
        self._kick = np.sqrt(2.0 * dt / params.error_correlation_time)

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
        self.w_gap[ids] = self._decay * self.w_gap[ids] + self._kick * xi[0, ids]
        self.w_ttc[ids] = self._decay * self.w_ttc[ids] + self._kick * xi[1, ids]

    def _delayed(self, hist: FloatArray, step: int, cols: IntArray, tau: float) -> FloatArray:
        lag = tau / self.dt
        j = int(np.floor(lag + 1e-9))
        r = max(lag - j, 0.0)
        now = hist[(step - j) % self.size, cols]
        if r == 0.0:
            return now
        return (1.0 - r) * now + r * hist[(step - j - 1) % self.size, cols]

    def perceive(
        self, step: int, ids: IntArray, leader: IntArray, leader_length: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Delayed, noisy ``(s_est, v, v_leader_est)`` of HDVs ``ids`` behind ``leader``.

        ``leader`` is -1 where there is none: the gap is then infinite.
        """
        p = self.params
        has = leader >= 0
        lead = np.where(has, leader, ids)
        x_i = self._delayed(self.x_hist, step, ids, p.reaction_time_gap)
        x_l = self._delayed(self.x_hist, step, lead, p.reaction_time_gap)
        s = np.where(has, x_l - leader_length - x_i, np.inf)
        v = self._delayed(self.v_hist, step, ids, p.reaction_time_speed)
        dv = self._delayed(self.v_hist, step, ids, p.reaction_time_approach) - self._delayed(
            self.v_hist, step, lead, p.reaction_time_approach
        )
        if self.errors:
            s_true = np.where(has, s, 0.0)
            dv = dv + s_true * p.inverse_ttc_error * self.w_ttc[ids]
            s = s * np.exp(p.gap_error * self.w_gap[ids])
        return s, v, v - np.where(has, dv, 0.0)
