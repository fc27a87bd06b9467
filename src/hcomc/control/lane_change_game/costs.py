r"""Cost model of the discretionary lane-change game (paper Section III-B).

The simulated cost :math:`J = w_s J_s + w_e J_e + w_c J_c` of every joint action over the
horizon, from the players' motion predicted by :mod:`hcomc.control.lane_change_game.players`,
under the actions and parameters of :mod:`hcomc.control.lane_change_game.params`; the
assumptions behind them are listed in :mod:`hcomc.control.lane_change_game.decision`, whose
:func:`~hcomc.control.lane_change_game.decision.lane_change_game` builds the cost matrices from
these functions and solves the game.
"""

from __future__ import annotations

import numpy as np

from hcomc._typing import BoolArray, FloatArray
from hcomc.control.lane_change_game import game_safety
from hcomc.control.lane_change_game.game_safety import INFEASIBLE_SAFETY_COST
from hcomc.control.lane_change_game.params import GameParams
from hcomc.equations.safety import critical_acceleration

__all__ = [
    "INFEASIBLE_SAFETY_COST",
    "comfort_cost",
    "efficiency_cost",
    "safety_cost",
    "worst_critical_acceleration",
]


def worst_critical_acceleration(
    gap: FloatArray,
    v_rear: FloatArray,
    v_front: FloatArray,
    delay: float,
    active: BoolArray,
    params: GameParams,
) -> FloatArray:
    """The worst Eq. 15 a_cr [m/s^2] over the last (time) axis on the active entries.

    ``+inf`` when an active entry is infeasible: a gap ``<= 0`` (overlap) or a required
    deceleration that cannot be braked (a_cr infinite or above a_merg, the emergency
    deceleration, which the follower cannot exceed); 0 without an active entry.
    """
    a_cr = critical_acceleration(
        gap,
        v_rear,
        v_front,
        delay=delay,
        min_distance=params.min_distance,
        emergency_decel=params.emergency_decel,
    )
    bad = active & ((gap <= 0.0) | ~(a_cr <= params.emergency_decel))
    worst = np.where(active & ~bad, a_cr, 0.0).max(axis=-1)
    return np.asarray(np.where(bad.any(axis=-1), np.inf, worst), dtype=np.float64)


def safety_cost(
    gap: FloatArray,
    v_rear: FloatArray,
    v_front: FloatArray,
    delay: float,
    active: BoolArray,
    params: GameParams,
) -> FloatArray:
    """J_s over the last (time) axis: the shared safety term
    (:func:`hcomc.control.lane_change_game.game_safety.safety_term`, a_cr / a_merg) of the
    worst Eq. 15 value on the active entries (:func:`worst_critical_acceleration`);
    :data:`INFEASIBLE_SAFETY_COST` for an infeasible entry, 0 without an active entry."""
    worst = worst_critical_acceleration(gap, v_rear, v_front, delay, active, params)
    return game_safety.safety_term(worst, params.emergency_decel)


def efficiency_cost(v: FloatArray, v0: float) -> FloatArray:
    """J_e = mean over the last axis of |v - v0| / v0 [-]."""
    return np.asarray(np.mean(np.abs(v - v0), axis=-1) / v0, dtype=np.float64)


def comfort_cost(
    a_lon: FloatArray,
    a_lat: FloatArray,
    a_max: FloatArray | float,
    b_comf: FloatArray | float,
    params: GameParams,
) -> FloatArray:
    """J_c = max|jerk|/j_max + mean[(a_x/a_ref)^2 + (a_y/a_max)^2] over the last axis.

    The jerk is the finite difference of the acceleration series preceded by 0; longitudinal and
    lateral parts combine as a vector norm. ``a_ref`` is ``a_max`` for ``a_x >= 0`` and
    ``b_comf`` for braking. ``a_max``/``b_comf`` broadcast against the leading axes.
    """
    a_max = np.asarray(a_max, dtype=np.float64)[..., None]
    b_comf = np.asarray(b_comf, dtype=np.float64)[..., None]
    pad = np.zeros((*a_lon.shape[:-1], 1))
    j_lon = np.diff(np.concatenate([pad, a_lon], axis=-1), axis=-1) / params.dt
    j_lat = np.diff(np.concatenate([pad, a_lat], axis=-1), axis=-1) / params.dt
    # |jerk| from exactly rounded operations (numpy's hypot is chosen by the CPU)
    jerk = np.sqrt(j_lon * j_lon + j_lat * j_lat).max(axis=-1)
    ref = np.where(a_lon >= 0.0, a_max, b_comf)
    mean_sq = np.mean(np.square(a_lon / ref) + np.square(a_lat / a_max), axis=-1)
    return np.asarray(jerk / params.jerk_max + mean_sq, dtype=np.float64)
