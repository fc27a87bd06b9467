r"""Cost model of the discretionary lane-change game (paper Section III-B).

Players, actions, parameters (:class:`GameParams`, driver types) and the simulated cost
:math:`J = w_s J_s + w_e J_e + w_c J_c` of every joint action over the horizon; the
assumptions behind them are listed in :mod:`hcomc.control.lane_change_game`, whose
:func:`~hcomc.control.lane_change_game.lane_change_game` builds the cost matrices from these
functions and solves the game.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray
from hcomc.config import ControlParams, IDMParams, LaneChangeParams, RoadParams
from hcomc.models.idm import idm_accel, iidm_accel
from hcomc.models.quintic import quintic_shape
from hcomc.models.transition import blend, transition_gamma, transition_psi
from hcomc.road import Kind
from hcomc.safety.critical import critical_acceleration

if TYPE_CHECKING:
    from hcomc.config import ScenarioConfig
    from hcomc.sim.fleet import Fleet

__all__ = [
    "FV_AC",
    "FV_ACTIONS",
    "FV_CS",
    "FV_DC",
    "FV_LC",
    "GAME_DEFAULT",
    "INFEASIBLE_SAFETY_COST",
    "SV_ACTIONS",
    "SV_K",
    "SV_LC",
    "DriverType",
    "GameParams",
    "GameVehicle",
    "comfort_cost",
    "efficiency_cost",
    "fv_kinematics",
    "game_params",
    "game_vehicle",
    "lateral_accel",
    "leader_track",
    "safety_cost",
    "simulate_sv",
]

SV_LC: int = 0
"""SV action index: change lane."""
SV_K: int = 1
"""SV action index: keep following in the current lane."""
SV_ACTIONS: tuple[str, ...] = ("LC", "K")
"""Names of the SV actions, by index."""

FV_LC: int = 0
"""FV action index: change lane (leave the target lane)."""
FV_CS: int = 1
"""FV action index: constant speed."""
FV_AC: int = 2
"""FV action index: accelerate at ``+fv_accel``."""
FV_DC: int = 3
"""FV action index: decelerate at ``-fv_accel``."""
FV_ACTIONS: tuple[str, ...] = ("LC", "CS", "AC", "DC")
"""Names of the FV actions, by index."""

INFEASIBLE_SAFETY_COST: float = 10.0
"""J_s of an overlapping gap or an unavoidable crash (a_cr = inf or > a_merg) [-]."""


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class DriverType(_Frozen):
    """A Harsanyi driver type (driving style) of the follower.

    The IDM parameters and cost weights are suggestions (docs/models.md); the paper gives none.
    """

    name: str = Field(min_length=1, description="type name, e.g. 'normal' [-]")
    time_headway: float = Field(gt=0, le=10, description="T, IDM desired time gap [s]")
    max_accel: float = Field(gt=0, le=10, description="a, maximum acceleration [m/s^2]")
    comfort_decel: float = Field(gt=0, le=10, description="b, comfortable deceleration [m/s^2]")
    w_safety: float = Field(ge=0, le=10, description="w_s, weight of the safety cost [-]")
    w_efficiency: float = Field(ge=0, le=10, description="w_e, weight of the efficiency cost [-]")
    w_comfort: float = Field(ge=0, le=10, description="w_c, weight of the comfort cost [-]")


AGGRESSIVE = DriverType(
    name="aggressive",
    time_headway=1.0,
    max_accel=2.0,
    comfort_decel=3.0,
    w_safety=0.2,
    w_efficiency=0.6,
    w_comfort=0.2,
)
"""Aggressive style (suggested values)."""
NORMAL = DriverType(
    name="normal",
    time_headway=1.5,
    max_accel=1.4,
    comfort_decel=2.0,
    w_safety=0.4,
    w_efficiency=0.4,
    w_comfort=0.2,
)
"""Normal style (suggested values)."""
CONSERVATIVE = DriverType(
    name="conservative",
    time_headway=2.0,
    max_accel=1.0,
    comfort_decel=1.5,
    w_safety=0.6,
    w_efficiency=0.2,
    w_comfort=0.2,
)
"""Conservative style (suggested values)."""


def _default(model: type[BaseModel], name: str) -> float:
    """The scenario config's default of ``name`` (its one home), as a game default."""
    return float(model.model_fields[name].default)


class GameParams(_Frozen):
    """Parameters of the discretionary lane-change game (paper §III-B).

    The paper states none of the weights, priors or type parameters; the defaults are the
    suggestions of docs/models.md (prior 0.25/0.5/0.25, SV weights 0.5/0.3/0.2). The
    Eq. 15 values, the threshold, ``lane_width`` and ``transition_tolerance`` (used by the
    lateral comfort term and the Eq. 14 transition) belong to the scenario config: their
    defaults here are read from it, and :func:`game_params` copies a config's values.
    """

    types: tuple[DriverType, ...] = Field(
        (AGGRESSIVE, NORMAL, CONSERVATIVE),
        min_length=1,
        description="Harsanyi types of an HDV follower (unique names) [-]",
    )
    prior: tuple[float, ...] = Field(
        (0.25, 0.5, 0.25), description="prior probability of each type, sums to 1 [-]"
    )
    sv_weights: tuple[float, float, float] = Field(
        (0.5, 0.3, 0.2), description="SV cost weights (w_s, w_e, w_c), non-negative [-]"
    )
    fv_accel: float = Field(1.0, gt=0, le=10, description="magnitude of FV's AC/DC [m/s^2]")
    horizon: float = Field(4.0, gt=0, le=30, description="H = T_lc, simulation horizon [s]")
    dt: float = Field(0.25, gt=0, le=2, description="prediction step, divides horizon [s]")
    safety_threshold: float = Field(
        _default(ControlParams, "safety_threshold"),
        gt=0,
        le=20,
        description="a_th, critical acceleration mapped to J_s = 1 [m/s^2]",
    )
    jerk_max: float = Field(5.0, gt=0, le=100, description="j_max, jerk normaliser [m/s^3]")
    delay_cav: float = Field(
        _default(ControlParams, "safety_delay_cav"),
        ge=0,
        le=5,
        description="Eq. 15 delay T, CAV follower [s]",
    )
    delay_hdv: float = Field(
        _default(ControlParams, "safety_delay_hdv"),
        ge=0,
        le=5,
        description="Eq. 15 delay T, HDV follower [s]",
    )
    min_distance: float = Field(
        _default(ControlParams, "safety_min_distance"),
        ge=0,
        le=50,
        description="Eq. 15 residual distance D [m]",
    )
    emergency_decel: float = Field(
        _default(ControlParams, "safety_emergency_decel"),
        gt=0,
        le=15,
        description="Eq. 15 a_merg, emergency deceleration [m/s^2]",
    )
    lane_width: float = Field(
        _default(RoadParams, "lane_width"),
        gt=0,
        le=10,
        description="W, lateral lane-change offset [m]",
    )
    transition_tolerance: float = Field(
        _default(LaneChangeParams, "transition_tolerance"),
        gt=0,
        lt=0.5,
        description="epsilon of the Eq. 14 transition, Psi(0) = eps [-]",
    )

    @model_validator(mode="after")
    def _consistent(self) -> GameParams:
        names = [t.name for t in self.types]
        if len(set(names)) != len(names):
            raise ValueError(f"type names must be unique, got {names}")
        if len(self.prior) != len(self.types):
            raise ValueError(
                f"prior has {len(self.prior)} entries for {len(self.types)} types: {self.prior}"
            )
        if any(not np.isfinite(p) or p < 0.0 for p in self.prior):
            raise ValueError(f"prior entries must be finite and >= 0, got {self.prior}")
        if abs(sum(self.prior) - 1.0) > 1e-9:
            raise ValueError(f"prior must sum to 1, got {sum(self.prior)!r} for {self.prior}")
        if any(not np.isfinite(w) or w < 0.0 for w in self.sv_weights):
            raise ValueError(f"sv_weights must be finite and >= 0, got {self.sv_weights}")
        ratio = self.horizon / self.dt
        if abs(ratio - round(ratio)) > 1e-9:
            raise ValueError(f"horizon = {self.horizon} must be a multiple of dt = {self.dt}")
        return self

    @property
    def n_steps(self) -> int:
        """Number N of prediction steps, ``horizon / dt``."""
        return round(self.horizon / self.dt)

    @property
    def reference_type(self) -> int:
        """Index of the type whose weights a CAV follower uses: 'normal', else the modal type."""
        for i, t in enumerate(self.types):
            if t.name == "normal":
                return i
        return int(np.argmax(self.prior))


GAME_DEFAULT: GameParams = GameParams()
"""Default game parameters (those of the default scenario config)."""


def game_params(config: ScenarioConfig) -> GameParams:
    """The default game with the Eq. 15 parameters and threshold of ``config.control``.

    Every consumer of the game (the HCOMC controller, the engine's CAV lane changes) builds its
    parameters here, so the Eq. 15 values have one home: the config.
    """
    c = config.control
    return GAME_DEFAULT.model_copy(
        update={
            "safety_threshold": c.safety_threshold,
            "delay_cav": c.safety_delay_cav,
            "delay_hdv": c.safety_delay_hdv,
            "min_distance": c.safety_min_distance,
            "emergency_decel": c.safety_emergency_decel,
            "lane_width": config.road.lane_width,
            "transition_tolerance": config.lane_change.transition_tolerance,
        }
    )


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


def leader_track(leader: GameVehicle | None, t: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Rear-bumper position (N,) [m] and speed (N,) [m/s] of a constant-speed leader at ``t``.

    An absent leader is at ``+inf`` with speed 0, so every gap to it is ``+inf`` (IDM free road,
    Eq. 15 gives 0).
    """
    if leader is None:
        return np.full(t.shape, np.inf), np.zeros(t.shape)
    rear = leader.x - leader.length + leader.v * t
    return rear, np.full(t.shape, float(leader.v))


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
    old_rear, old_v = leader_track(old, t_start)
    new_rear, new_v = leader_track(new, t_start)
    car_following = (
        float(sv.desired_speed),
        idm.time_headway,
        idm.max_accel,
        idm.comfort_decel,
        idm.min_gap,
        idm.exponent,
        idm.variant == "iidm",
    )
    return _simulate_sv_kernel(
        float(sv.x), float(sv.v), old_rear, old_v, new_rear, new_v, *car_following,
        dt, params.horizon, transition_gamma(params.transition_tolerance),
        params.emergency_decel,
    )  # fmt: skip


@kernel
def _simulate_sv_kernel(
    x0, v_start, old_rear, old_v, new_rear, new_v, v0, T, a_max, b, s0, delta, iidm, dt,
    horizon, gamma, emergency_decel,
):  # fmt: skip
    """:func:`simulate_sv`'s loop: row 0 (LC) with Ψ(t_{k-1}) of Eq. 14, row 1 (K) with
    weight 0; the car-following law is :func:`~hcomc.models.idm.iidm_accel` if ``iidm``,
    else :func:`~hcomc.models.idm.idm_accel`."""
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
            v_next = v + a * dt
            if v_next < 0.0:  # stops within the step
                dx = v * v / (2.0 * -a)
                v_next = 0.0
            else:
                dx = v * dt + 0.5 * a * dt * dt
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


def safety_cost(
    gap: FloatArray,
    v_rear: FloatArray,
    v_front: FloatArray,
    delay: float,
    active: BoolArray,
    params: GameParams,
) -> FloatArray:
    """J_s over the last (time) axis from Eq. 15 on the active entries; inactive entries = 0."""
    a_cr = critical_acceleration(
        gap,
        v_rear,
        v_front,
        delay=delay,
        min_distance=params.min_distance,
        emergency_decel=params.emergency_decel,
    )
    bad = active & ((gap <= 0.0) | ~(a_cr <= params.emergency_decel))
    worst = np.where(active, np.where(bad, 0.0, a_cr), 0.0).max(axis=-1)
    j_s = np.minimum(1.0, worst / params.safety_threshold)
    return np.where(bad.any(axis=-1), INFEASIBLE_SAFETY_COST, j_s)


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
    jerk = np.hypot(j_lon, j_lat).max(axis=-1)
    ref = np.where(a_lon >= 0.0, a_max, b_comf)
    mean_sq = np.mean(np.square(a_lon / ref) + np.square(a_lat / a_max), axis=-1)
    return np.asarray(jerk / params.jerk_max + mean_sq, dtype=np.float64)


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
