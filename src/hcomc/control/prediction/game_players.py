r"""The lane-change game's players over its horizon (paper Section III-B).

The subject vehicle SV follows its car-following model behind the old and the new leader, blended
by the tanh transition of Eq. 14 while it changes lane (:func:`simulate_sv`, integrated with the
engine's ballistic step); the follower FV's actions are closed-form constant accelerations
(:func:`fv_kinematics`); SV's lateral motion is the quintic of Eq. 4 (:func:`lateral_accel`).
The leaders cruise at constant speed. :mod:`hcomc.control.lane_change_game.costs` scores these
motions and :mod:`hcomc.control.lane_change_game.decision` plays the game on the scores; HCOMC's
merge problem also simulates SV with :func:`simulate_sv` for a lateral cooperation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.config import IDMParams
from hcomc.control.lane_change_game.params import GameParams
from hcomc.models.ballistic import ballistic_step
from hcomc.models.idm import idm_accel
from hcomc.models.iidm import iidm_accel
from hcomc.models.quintic import quintic_shape
from hcomc.models.transition import blend, transition_gamma, transition_psi
from hcomc.road import Kind

if TYPE_CHECKING:
    from hcomc.interface import Fleet

__all__ = [
    "CarFollowing",
    "GameVehicle",
    "LeaderTrack",
    "Manoeuvre",
    "fv_kinematics",
    "game_vehicle",
    "lateral_accel",
    "leader_track",
    "simulate_sv",
]


@dataclass(frozen=True)
class GameVehicle:
    """Longitudinal state of one vehicle taking part in the game.

    Attributes
    ----------
    x : float
        Front-bumper position along the road [m].
    v : float
        Speed [m/s], ``>= 0``.
    length : float
        Vehicle length [m], ``> 0``.
    desired_speed : float
        Desired speed v0 [m/s], ``> 0`` (IDM v0 for SV, reference of the efficiency cost).
    is_cav : bool
        True for a CAV (Eq. 15 delay ``delay_cav``), False for an HDV.
    """

    x: float
    v: float
    length: float
    desired_speed: float
    is_cav: bool

    def __post_init__(self) -> None:
        if not np.isfinite(self.x):
            raise ValueError(f"x must be finite, got {self.x!r}")
        if not (np.isfinite(self.v) and self.v >= 0.0):
            raise ValueError(f"v must be finite and >= 0, got {self.v!r}")
        if not (np.isfinite(self.length) and self.length > 0.0):
            raise ValueError(f"length must be finite and > 0, got {self.length!r}")
        if not (np.isfinite(self.desired_speed) and self.desired_speed > 0.0):
            raise ValueError(f"desired_speed must be finite and > 0, got {self.desired_speed!r}")


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


def leader_track(leader: GameVehicle | None, t: FloatArray) -> LeaderTrack:
    """Rear-bumper position (N,) [m] and speed (N,) [m/s] of a constant-speed leader at ``t``.

    An absent leader is at ``+inf`` with speed 0, so every gap to it is ``+inf`` (IDM free road,
    Eq. 15 gives 0).
    """
    if leader is None:
        return LeaderTrack(np.full(t.shape, np.inf), np.zeros(t.shape))
    rear = leader.x - leader.length + leader.v * t
    return LeaderTrack(rear, np.full(t.shape, float(leader.v)))


def simulate_sv(
    sv: GameVehicle,
    old: GameVehicle | None,
    new: GameVehicle | None,
    idm: IDMParams,
    params: GameParams,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Positions, speeds and applied accelerations (2, N) of SV for actions (LC, K).

    Ballistic update with a stop at v = 0; the IDM (or IIDM, per ``idm.variant``) output is
    floored at ``-emergency_decel``. Row LC blends the accelerations towards ``old`` and
    ``new`` with Eq. 14 (Ψ at the start of each step, τ = t_{k-1}); row K follows ``old``.
    The loop over the N time steps is compiled (:func:`_simulate_sv_kernel`).
    """
    n, dt = params.n_steps, params.dt
    t_start: FloatArray = dt * np.arange(n, dtype=np.float64)
    model = CarFollowing(
        float(sv.desired_speed),
        idm.time_headway,
        idm.max_accel,
        idm.comfort_decel,
        idm.min_gap,
        idm.exponent,
        idm.variant == "iidm",
    )
    manoeuvre = Manoeuvre(
        dt, params.horizon, transition_gamma(params.transition_tolerance), params.emergency_decel
    )
    return _simulate_sv_kernel(
        float(sv.x), float(sv.v), leader_track(old, t_start), leader_track(new, t_start), model,
        manoeuvre,
    )  # fmt: skip


@kernel
def _simulate_sv_kernel(
    x0: float, v_start: float, old: LeaderTrack, new: LeaderTrack, model: CarFollowing,
    manoeuvre: Manoeuvre,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """:func:`simulate_sv`'s loop from SV's position ``x0`` and speed ``v_start`` behind the
    ``old`` and ``new`` leaders: row 0 (LC) with Ψ(t_{k-1}) of Eq. 14, row 1 (K) with
    weight 0; the car-following law is :func:`~hcomc.models.iidm.iidm_accel` if
    ``model.iidm``, else :func:`~hcomc.models.idm.idm_accel`."""
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


def fv_kinematics(
    fv: GameVehicle, t: FloatArray, params: GameParams
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Closed-form positions, speeds and applied accelerations (4, N) of FV's actions.

    LC and CS cruise, AC/DC hold ``±fv_accel``; DC stops at v = 0 and stays there.
    """
    a = np.array([0.0, 0.0, params.fv_accel, -params.fv_accel])[:, None]  # (4, 1)
    t_stop = np.where(a < 0.0, fv.v / np.where(a < 0.0, -a, 1.0), np.inf)
    te = np.minimum(t[None, :], t_stop)  # (4, N)
    x = fv.x + fv.v * te + 0.5 * a * te * te
    v = np.maximum(fv.v + a * te, 0.0)
    v_prev = np.concatenate([np.full((4, 1), float(fv.v)), v[:, :-1]], axis=1)
    return x, v, (v - v_prev) / params.dt


def lateral_accel(t: FloatArray, params: GameParams) -> FloatArray:
    """Lateral acceleration (N,) of a rest-to-rest quintic lane change over H (Eq. 4) [m/s^2]."""
    _, _, ddp = quintic_shape(t / params.horizon)
    return params.lane_width / params.horizon**2 * ddp


def game_vehicle(x: FloatArray, v: FloatArray, fleet: Fleet, i: int) -> GameVehicle | None:
    """The :class:`GameVehicle` of vehicle ``i`` (None for -1, a missing vehicle)."""
    if i < 0:
        return None
    return GameVehicle(
        x=float(x[i]),
        v=float(v[i]),
        length=float(fleet.length[i]),
        desired_speed=float(fleet.v0[i]),
        is_cav=bool(fleet.kind[i] == Kind.CAV),
    )
