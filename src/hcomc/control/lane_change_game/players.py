r"""The lane-change game's players over its horizon (paper Section III-B).

The subject vehicle SV follows its car-following model behind the old and the new leader, blended
by the tanh transition of Eq. 14 while it changes lane (:func:`simulate_sv`, integrated with the
engine's ballistic step by the kernel
:func:`~hcomc.control.prediction.game_players.simulate_sv_kernel`); the follower FV's actions
are closed-form constant accelerations (:func:`fv_kinematics`); SV's lateral motion is the
quintic of Eq. 4 (:func:`lateral_accel`). The leaders cruise at constant speed
(:func:`leader_track`). :mod:`hcomc.control.lane_change_game.costs` scores these motions and
:mod:`hcomc.control.lane_change_game.decision` plays the game on the scores; HCOMC's merge
problem also simulates SV with :func:`simulate_sv` for a lateral cooperation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from hcomc._typing import FloatArray
from hcomc.config import IDMParams
from hcomc.control.lane_change_game.params import GameParams
from hcomc.control.prediction.game_players import (
    CarFollowing,
    LeaderTrack,
    Manoeuvre,
    simulate_sv_kernel,
)
from hcomc.equations.lane_change import quintic_shape
from hcomc.equations.transition import transition_gamma
from hcomc.road import Kind

if TYPE_CHECKING:
    from hcomc.interface import Fleet

__all__ = [
    "GameVehicle",
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
    The loop over the N time steps is compiled
    (:func:`~hcomc.control.prediction.game_players.simulate_sv_kernel`).
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
    return simulate_sv_kernel(
        float(sv.x), float(sv.v), leader_track(old, t_start), leader_track(new, t_start), model,
        manoeuvre,
    )  # fmt: skip


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
