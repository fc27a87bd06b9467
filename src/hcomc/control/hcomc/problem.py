"""The HCOMC multi-objective merge problem (paper Eq. 15-18; MODELS.md §7, §8, §14).

Decision vector (one row per candidate plan):

====  ==========================================================  =====================
col   variable                                                    bounds
====  ==========================================================  =====================
0     VR's lane-change start position on the acceleration lane     [accel start, end - 3L] m
1     VR's lane-change duration                                     [3, 6] s
2     planning horizon H = tf' - t0' of the virtual vehicle         [4, 20] s (config)
3     VMC's cooperation mode (< 0.5 longitudinal, >= 0.5 lateral)   [0, 1]
====  ==========================================================  =====================

Objectives, all minimised (columns named for :func:`hcomc.optim.selection.select_eq19`):

* ``safety`` — U_safe, the worst Eq. 15 critical acceleration over consecutive same-lane pairs
  of the key vehicles at merge completion [m/s^2];
* ``fuel`` — U_fuel, Eq. 16 fuel of VR and VMC over the prediction window [L];
* ``efficiency`` — −U_eff, Eq. 17 with politeness eta over VMC, VMR and VNR [m/s^2].

Constraints (feasible when <= 0): predicted rectangle collisions among the key vehicles
(count of colliding pair-steps), merge not completed in the window, an unavoidable crash in
Eq. 15 (infinite U_safe), an infeasible virtual vehicle (v < 0 or a < -b_max), a lane change
that would end beyond the acceleration lane [m], lateral mode not admitted by the lane-change
game (or VMC not a CAV).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.control.hcomc.rollout import (
    C_A_MERG,
    C_ACCEL_END,
    C_D,
    C_DT,
    C_EMERGENCY,
    C_GAMMA,
    C_POLITENESS,
    C_VMC_DUR,
    C_VV_DECEL,
    C_WIDTH,
    G_COLLISION,
    N_CONSTS,
    N_ROLES,
    P_LEN,
    P_WID,
    VMC,
    VR,
    rollout,
)
from hcomc.models.fuel import fuel_rate
from hcomc.safety.collision import vehicles_collide

OBJECTIVES = ("safety", "fuel", "efficiency")
CONSTRAINTS = ("collision", "not_merged", "unsafe", "virtual_vehicle", "overrun", "lateral")
_PAIRS = np.array([(i, j) for i in range(N_ROLES) for j in range(i + 1, N_ROLES)])


@dataclass(frozen=True, slots=True)
class KeyState:
    """State and parameters of the six key vehicles at planning time (roles VR … VNR).

    Missing VMF/VNF are replaced by a phantom far ahead at VMC's speed (free road); missing
    VMR/VNR are absent (``present`` False).
    """

    t0: float
    x: FloatArray
    v: FloatArray
    a: FloatArray
    present: BoolArray
    cav: BoolArray
    params: FloatArray  # (6, 9): v0, T, s0, a, b, delta, coolness, length, width
    ids: IntArray  # (6,) vehicle indices in the simulation, -1 for absent or phantom


@dataclass(frozen=True, slots=True)
class Prediction:
    """Predicted trajectories (C, K + 1, 6) and objective parts of candidate plans."""

    t: FloatArray
    X: FloatArray
    Y: FloatArray
    V: FloatArray
    A: FloatArray
    heading: FloatArray
    k_merge: IntArray
    F: FloatArray
    G: FloatArray
    vv1: FloatArray
    vv2: FloatArray


class MergeProblem:
    """Vectorised HCOMC problem for one planning instant (implements ``optim.base.Problem``)."""

    n_var = 4
    n_obj = 3
    n_constr = len(CONSTRAINTS)
    objective_names = OBJECTIVES

    def __init__(
        self,
        state: KeyState,
        *,
        accel_lane: tuple[float, float],
        lane_width: float,
        lateral_allowed: bool,
        vmc_duration: float,
        transition_tolerance: float,
        emergency_decel: float,
        politeness: float,
        virtual_max_decel: float,
        prediction_dt: float,
        horizon: tuple[float, float],
        post_merge: float,
        min_distance: float = 2.0,
        emergency_brake: float = 7.5,
    ) -> None:
        self.state = state
        self.lateral_allowed = lateral_allowed
        start, end = accel_lane
        length = float(state.params[VR, P_LEN])
        self.xl = np.array([max(start, state.x[VR] + 1.0), 3.0, horizon[0], 0.0])
        self.xu = np.array([max(end - 3.0 * length, self.xl[0] + 1.0), 6.0, horizon[1], 1.0])
        consts = np.zeros(N_CONSTS)
        consts[C_DT] = prediction_dt
        consts[C_ACCEL_END] = end
        consts[C_WIDTH] = lane_width
        consts[C_VMC_DUR] = vmc_duration
        consts[C_GAMMA] = np.arctanh(1.0 - 2.0 * transition_tolerance)
        consts[C_EMERGENCY] = emergency_decel
        consts[C_VV_DECEL] = virtual_max_decel
        consts[C_POLITENESS] = politeness
        consts[C_D] = min_distance
        consts[C_A_MERG] = emergency_brake
        self.consts = consts
        # window: VR reaches the lane end at its current speed, changes lane, then settles
        reach = (end - state.x[VR]) / max(state.v[VR], 5.0)
        self.n_steps = int(np.ceil((reach + self.xu[1] + post_merge) / prediction_dt))
        self.dt = prediction_dt
        self._fuel_ref = self._reference_fuel()

    def _reference_fuel(self) -> float:
        """Cruise fuel of VR and VMC at their current speeds over the window [L] (scaling)."""
        s = self.state
        v = np.array([s.v[VR], s.v[VMC] if s.present[VMC] else 0.0])
        return float(fuel_rate(v, 0.0).sum() * self.n_steps * self.dt / 1000.0)

    # ------------------------------------------------------------------ evaluate
    def predict(self, X: FloatArray) -> Prediction:
        """Roll out every candidate row of ``X`` and compute its objectives and constraints."""
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        s = self.state
        lateral = X[:, 3] >= 0.5
        Xt, Yt, Vt, At, Ht, k_merge, u_safe, u_eff, g, vv1, vv2, near = rollout(
            s.x, s.v, s.a, s.present, s.cav, s.params,
            X[:, 0].copy(), X[:, 1].copy(), X[:, 2].copy(), lateral, self.consts, self.n_steps,
        )  # fmt: skip
        G = np.zeros((X.shape[0], self.n_constr))
        G[:, : g.shape[1]] = g
        G[:, G_COLLISION] = self._collisions(Xt, Yt, Ht, near)
        G[:, -1] = np.where(lateral & ~self.lateral_allowed, 1.0, 0.0)
        fuel = fuel_rate(Vt[:, :, [VR, VMC]], At[:, :, [VR, VMC]]).sum(axis=(1, 2)) * self.dt
        F = np.column_stack([np.minimum(u_safe, 1e3), fuel / 1000.0, -u_eff])
        t = np.arange(self.n_steps + 1) * self.dt
        return Prediction(t, Xt, Yt, Vt, At, Ht, k_merge, F, G, vv1, vv2)

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Objectives (n, 3) and constraints (n, 6) of candidate rows ``X`` (n, 4)."""
        p = self.predict(X)
        return p.F, p.G

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        """Eq. 19 as one cost for PSO and SA, with the U_safe <= 4 gate as a penalty.

        ``U = U_fuel / U_fuel,ref + (-U_eff) / (1 m/s^2) + 10 max(0, U_safe - 4)
        + 1000 sum(max(G, 0))``: Eq. 19's sum of the two normalised costs with fixed scales
        (a single-objective optimiser has no Pareto set to min-max normalise over); the
        reference fuel is VR's and VMC's cruise fuel over the window.
        """
        penalty = 10.0 * np.maximum(F[:, 0] - 4.0, 0.0) + 1000.0 * np.maximum(G, 0.0).sum(axis=1)
        return F[:, 1] / self._fuel_ref + F[:, 2] + penalty

    # ----------------------------------------------------------------- helpers
    def _collisions(
        self, X: FloatArray, Y: FloatArray, H: FloatArray, near: BoolArray
    ) -> FloatArray:
        """Colliding (pair, step) count per candidate: oriented rectangles (Eq. 7).

        The kernel flags pairs whose bounding boxes overlap (``near``); the exact test of
        :func:`hcomc.safety.collision.vehicles_collide` runs on those only.
        """
        count = np.zeros(X.shape[0])
        if not near.any():
            return count
        s = self.state
        length, width = s.params[:, P_LEN], s.params[:, P_WID]
        c, k, p = np.nonzero(near)
        a, b = _PAIRS[p, 0], _PAIRS[p, 1]
        hit = vehicles_collide(
            X[c, k, a], Y[c, k, a], H[c, k, a], length[a], width[a],
            X[c, k, b], Y[c, k, b], H[c, k, b], length[b], width[b],
        )  # fmt: skip
        np.add.at(count, c[hit], 1.0)
        return count
