"""Players' actions and parameters of the discretionary lane-change game (paper Section III-B).

The action indices of the subject vehicle SV and of the follower FV, the Harsanyi driver types
of an HDV follower (:class:`DriverType`) and the game's parameters (:class:`GameParams`: types,
prior, weights, horizon and the Eq. 15 values, these read from the scenario config by
:func:`game_params`). The players' motion simulated with them is in
:mod:`hcomc.control.lane_change_game.players`, the costs in
:mod:`hcomc.control.lane_change_game.costs`; the assumptions behind them are listed in
:mod:`hcomc.control.lane_change_game.decision`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from pydantic import BaseModel, Field, model_validator

from hcomc.config import ControlParams, LaneChangeParams, RoadParams
from hcomc.config.frozen_model import FrozenModel

if TYPE_CHECKING:
    from hcomc.config import ScenarioConfig

__all__ = [
    "FV_AC",
    "FV_ACTIONS",
    "FV_CS",
    "FV_DC",
    "FV_LC",
    "GAME_DEFAULT",
    "SV_ACTIONS",
    "SV_K",
    "SV_LC",
    "DriverType",
    "GameParams",
    "game_params",
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


class DriverType(FrozenModel):
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


class GameParams(FrozenModel):
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
        description="a_th, a_cr bound of the added safety rule (not in J_s) [m/s^2]",
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


def game_params(config: ScenarioConfig, lane_width: float) -> GameParams:
    """The default game with the Eq. 15 parameters and threshold of ``config.control``, on
    lanes ``lane_width`` [m] wide.

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
            "lane_width": lane_width,
            "transition_tolerance": config.lane_change.transition_tolerance,
        }
    )
