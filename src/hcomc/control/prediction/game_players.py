r"""The lane-change game's subject vehicle over the horizon, compiled (paper Section III-B).

SV follows its car-following model behind the old and the new leader, blended by the tanh
transition of Eq. 14 while it changes lane, integrated with the engine's ballistic step
(:func:`simulate_sv_kernel`, on the records :class:`LeaderTrack`, :class:`CarFollowing` and
:class:`Manoeuvre`). :func:`hcomc.control.lane_change_game.players.simulate_sv` builds these
records from the game's parameters and calls it; the kernel stays apart from them so that its
cache depends on the models it integrates alone, not on the config.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc.equations.idm import idm_accel
from hcomc.equations.iidm import iidm_accel
from hcomc.equations.integrate import ballistic_step
from hcomc.equations.transition import blend, transition_psi

__all__ = ["CarFollowing", "LeaderTrack", "Manoeuvre", "simulate_sv_kernel"]


class LeaderTrack(NamedTuple):
    """A leader's motion over the horizon, each (N,) at the sample times."""

    rear: np.ndarray  # rear-bumper position [m] (+inf: no leader)
    v: np.ndarray  # speed [m/s]


class CarFollowing(NamedTuple):
    """SV's car-following model (:class:`~hcomc.config.IDMParams` with SV's desired speed)."""

    v0: float  # desired speed [m/s]
    T: float  # time headway [s]
    a_max: float  # maximum acceleration [m/s^2]
    b: float  # comfortable deceleration [m/s^2]
    s0: float  # minimum gap [m]
    delta: float  # acceleration exponent [-]
    iidm: bool  # the IIDM (else the IDM)


class Manoeuvre(NamedTuple):
    """How SV's motion over the horizon is integrated and blended (Eq. 14)."""

    dt: float  # time step [s]
    horizon: float  # lane-change duration H [s]
    gamma: float  # γ of the Eq. 14 transition [-] (from its tolerance ε)
    emergency_decel: float  # floor of the applied deceleration [m/s^2], > 0


@kernel
def simulate_sv_kernel(
    x0: float, v_start: float, old: LeaderTrack, new: LeaderTrack, model: CarFollowing,
    manoeuvre: Manoeuvre,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """:func:`~hcomc.control.lane_change_game.players.simulate_sv`'s loop from SV's position
    ``x0`` and speed ``v_start`` behind the ``old`` and ``new`` leaders: row 0 (LC) with
    Ψ(t_{k-1}) of Eq. 14, row 1 (K) with weight 0; the car-following law is
    :func:`~hcomc.equations.iidm.iidm_accel` if ``model.iidm``, else
    :func:`~hcomc.equations.idm.idm_accel`."""
    old_rear, old_v = old
    new_rear, new_v = new
    v0, T, a_max, b, s0, delta, iidm = model
    dt, horizon, gamma, emergency_decel = manoeuvre
    n = old_rear.size
    xs, vs, acc = np.empty((2, n)), np.empty((2, n)), np.empty((2, n))
    for row in range(2):
        x, v = x0, v_start
        for k in range(n):
            s_ori, dv_ori = old_rear[k] - x, v - old_v[k]
            s_new, dv_new = new_rear[k] - x, v - new_v[k]
            if iidm:
                a_ori = iidm_accel(s_ori, v, dv_ori, v0, T, a_max, b, s0, delta)
                a_new = iidm_accel(s_new, v, dv_new, v0, T, a_max, b, s0, delta)
            else:
                a_ori = idm_accel(s_ori, v, dv_ori, v0, T, a_max, b, s0, delta)
                a_new = idm_accel(s_new, v, dv_new, v0, T, a_max, b, s0, delta)
            weight = transition_psi(dt * k, horizon, gamma) if row == 0 else 0.0
            a = max(blend(a_ori, a_new, weight), -emergency_decel)
            dx, v_next, _ = ballistic_step(v, a, dt)
            acc[row, k] = (v_next - v) / dt
            x = x + dx
            v = v_next
            xs[row, k], vs[row, k] = x, v
    return xs, vs, acc
