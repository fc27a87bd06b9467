"""The vehicle tables of a scenario: car following of HDVs and CAVs, and lane changes.

``[hdv]`` and ``[cav]`` share the IDM parameters of Eq. (1) (:class:`IDMParams`); HDVs add the
reaction delays and estimation errors of Eq. (2), CAVs the coolness of the ACC of Eq. (3).
``[lane_change]`` holds the MOBIL decision and its execution, shared by both kinds. Units and
defaults are in each field's description (docs/models.md gives each one's source).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from hcomc.config.frozen_model import FrozenModel

__all__ = ["CAVParams", "HDVParams", "IDMParams", "LaneChangeParams"]


class IDMParams(FrozenModel):
    """Intelligent Driver Model parameters (paper Eq. 1; Treiber, Hennecke & Helbing 2000)."""

    desired_speed: float = Field(33.3, gt=0, le=70, description="v0, desired speed [m/s]")
    time_headway: float = Field(1.5, gt=0, le=10, description="T_s, safe time headway [s]")
    min_gap: float = Field(2.0, ge=0, le=20, description="s0, jam distance [m]")
    max_accel: float = Field(1.0, gt=0, le=10, description="a, maximum acceleration [m/s^2]")
    comfort_decel: float = Field(
        2.0, gt=0, le=10, description="b, comfortable deceleration [m/s^2]"
    )
    exponent: float = Field(4.0, gt=0, le=20, description="delta, acceleration exponent [-]")
    variant: Literal["idm", "iidm"] = Field(
        "idm", description="'idm' = Eq. 1; 'iidm' = improved IDM (Treiber & Kesting 2013)"
    )
    lane_change_duration: float = Field(
        4.0, gt=0.5, le=15, description="duration of a quintic lane change (Eq. 4-6) [s]"
    )


class HDVParams(IDMParams):
    """Human-driven vehicle: IDM with reaction delays and estimation errors (paper Eq. 2).

    Defaults follow the Human Driver Model (Treiber, Kesting & Helbing 2006): equal delays
    of 0.6 s for gap, speed and approach rate (the paper does not separate them), a
    log-normal relative gap error V_s = 0.05 and an inverse-TTC error sigma_r = 0.01 1/s,
    both Ornstein-Uhlenbeck processes with correlation time 20 s.
    """

    reaction_time_gap: float = Field(0.6, ge=0, le=3, description="tau_s, delay on the gap [s]")
    reaction_time_speed: float = Field(0.6, ge=0, le=3, description="tau_v, delay on own speed [s]")
    reaction_time_approach: float = Field(
        0.6, ge=0, le=3, description="tau_dv, delay on the approach rate [s]"
    )
    estimation_errors: bool = Field(True, description="switch the Wiener estimation errors on/off")
    gap_error: float = Field(0.05, ge=0, le=1, description="V_s, relative gap-estimation error [-]")
    inverse_ttc_error: float = Field(
        0.01, ge=0, le=1, description="sigma_r, error on the inverse TTC dv/s [1/s]"
    )
    error_correlation_time: float = Field(
        20.0, gt=0, le=1000, description="tau~, correlation time of the estimation errors [s]"
    )


class CAVParams(IDMParams):
    """Connected automated vehicle: ACC with the constant-acceleration heuristic (paper Eq. 3).

    Kesting et al. (2010) ACC values, with T = 1.0 s (CACC-like) and the
    coolness factor c = 0.99. Perception is exact and immediate.
    """

    time_headway: float = Field(1.0, gt=0, le=10, description="T_s, safe time headway [s]")
    max_accel: float = Field(1.4, gt=0, le=10, description="a, maximum acceleration [m/s^2]")
    coolness: float = Field(0.99, ge=0, le=1, description="c, coolness factor of Eq. 3 [-]")


class LaneChangeParams(FrozenModel):
    """MOBIL lane-change decisions (Kesting, Treiber & Helbing 2007) and their execution."""

    politeness: float = Field(0.5, ge=0, le=1, description="p (eta in Eq. 17), politeness [-]")
    threshold: float = Field(0.2, ge=0, le=5, description="Delta a_th, changing threshold [m/s^2]")
    keep_right_bias: float = Field(
        0.2, ge=0, le=5, description="Delta a_bias, keep-right bias towards lane 1 [m/s^2]"
    )
    safe_decel: float = Field(4.0, gt=0, le=10, description="b_safe, safety criterion [m/s^2]")
    min_gap: float = Field(2.0, ge=0, le=50, description="minimum bumper gap to accept [m]")
    decision_interval: float = Field(
        0.5, gt=0, le=10, description="time between lane-change decisions [s]"
    )
    transition_tolerance: float = Field(
        0.01, gt=0, lt=0.5, description="epsilon of the Eq. 14 tanh transition, Psi(0)=eps [-]"
    )
    emergency_decel: float = Field(
        9.0, gt=0, le=15, description="physical braking limit applied to every vehicle [m/s^2]"
    )
    exit_lookahead: float = Field(
        1000.0, gt=0, le=5000,
        description="a vehicle bound for an off-ramp, or in a lane that ends, starts moving "
        "right when its exit (or the lane's end) is within this distance per lane change "
        "still needed [m]; no lane of the paper's road ends nor leads off it",
    )  # fmt: skip
    urgent_distance: float = Field(
        100.0, ge=0, le=2000,
        description="within this distance of the last point of a change a vehicle's route "
        "or ending lane needs (an acceleration lane's end too), the deceleration it may "
        "impose on its new follower rises linearly from safe_decel to emergency_decel [m]",
    )  # fmt: skip
    cav_game: bool = Field(
        False,
        description="CAV discretionary changes accepted by MOBIL must also be the SV's "
        "equilibrium action of the Section III-B Stackelberg/Harsanyi game",
    )
