"""The ``[control]`` table of a scenario: the merge controller, its optimiser and the
parameters of its prediction, safety index and replanning (paper Section III).
"""

from __future__ import annotations

import re
from typing import Any, Literal

from pydantic import Field, field_validator

from hcomc.config.frozen_model import FrozenModel

__all__ = ["ControlParams"]

CONTROLLER_SPEC = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+-]*|[^:\s][^:]*:[A-Za-z_][A-Za-z0-9_]*")
"""A controller name: a registered name, or ``module:Class`` / ``path/to/file.py:Class``."""


class ControlParams(FrozenModel):
    """Merge controller and its optimiser (paper Section III)."""

    controller: str = Field(
        "none",
        description=(
            "merge controller; 'none' = gap acceptance only, 'hcomc' = the paper's controller, "
            "'fifo' / 'game' = the Table III baselines (FIFO sequencing, 2x2 merge game), "
            "'game-capped' = the merge game with a safety term capped at 1 (a variant), a name "
            "an installed package registers (entry-point group 'hcomc.controllers'), or a class "
            "of your own: 'package.module:Class' or 'path/to/file.py:Class'"
        ),
    )
    options: dict[str, Any] = Field(
        default_factory=dict,
        description="keyword arguments of the controller's constructor ([control.options] "
        "table), checked against its signature and type hints",
    )
    on_invalid_plan: Literal["error", "fallback"] = Field(
        "error",
        description="a plan that fails the checks of hcomc.control.validation: 'error' stops "
        "the run naming the field, the value and what is allowed; 'fallback' lets VR merge by "
        "gap acceptance and records the plan as a fallback",
    )
    optimizer: Literal["nsga2", "nsga2-pymoo", "pso", "pso-pymoo", "sa", "sa-scipy"] = Field(
        "nsga2",
        description=(
            "HCOMC optimiser; 'nsga2' = compiled NSGA-II, 'nsga2-pymoo' = the same algorithm "
            "through pymoo (slower; the same solution quality, not the same rows); "
            "'pso' / 'pso-pymoo' likewise for PSO; 'sa' = simulated annealing, 'sa-scipy' = the "
            "same through SciPy's dual_annealing"
        ),
    )
    budget: int = Field(
        360, ge=10, le=100_000, description="candidate evaluations per decision (all optimisers)"
    )
    pop_size: int = Field(40, ge=4, le=1000, description="population (NSGA-II, PSO)")
    prediction_dt: float = Field(0.25, gt=0, le=1, description="prediction step [s]")
    horizon_min: float = Field(4.0, gt=0, le=60, description="lower bound of H = tf' - t0' [s]")
    horizon_max: float = Field(
        20.0,
        gt=0,
        le=60,
        description="upper bound of H [s]; VR needs 12-15 s to cross the control zone",
    )
    post_merge: float = Field(
        5.0, ge=0, le=60, description="prediction window after the latest merge end [s]"
    )
    virtual_max_decel: float = Field(
        7.5,
        gt=0,
        le=15,
        description="b_max: a virtual vehicle braking harder is rejected (= a_merg) [m/s^2]",
    )
    safety_threshold: float = Field(
        4.0, gt=0, le=10, description="Eq. 19 gate on U_safe (= MOBIL b_safe) [m/s^2]"
    )
    safety_delay_cav: float = Field(
        0.5, ge=0, le=5, description="Eq. 15 delay T of a CAV follower [s]"
    )
    safety_delay_hdv: float = Field(
        1.0, ge=0, le=5, description="Eq. 15 delay T of an HDV follower (reaction + brake) [s]"
    )
    safety_min_distance: float = Field(
        2.0, ge=0, le=50, description="Eq. 15 residual distance D (= s0) [m]"
    )
    safety_emergency_decel: float = Field(
        7.5, gt=0, le=15, description="Eq. 15 a_merg, leader's emergency deceleration [m/s^2]"
    )
    replan_period: float = Field(
        0.0,
        ge=0,
        le=60,
        description="0 = plan once at VR's control-zone entry, as the paper (Section III); "
        "> 0: a receding horizon (an extension): re-identify the key vehicles and replan every "
        "this many seconds until VR starts its lane change [s]",
    )
    commitment_margin: float = Field(
        2.0,
        ge=0,
        le=2,
        description="HCOMC replanning keeps the live plan's cooperating vehicle, mode and "
        "sequence unless no feasible candidate keeps them, every one fails Eq. 19's safety gate, "
        "or the best new plan's Eq. 19 cost (min-max normalised over the candidates, range 0-2) "
        "is lower by more than this; 2 = never for cost alone (a replan corrects the plan, it "
        "does not re-choose it); 0 = always take the best [-]",
    )
    lateral_safety_rule: bool = Field(
        True,
        description="HCOMC admits VMC's lateral cooperation when the Section III-B lane-change "
        "game's equilibrium is to change lane, or (an extension, not in the paper) when that "
        "change keeps Eq. 15's a_cr below safety_threshold against every response its follower "
        "plays; false = the equilibrium alone (the configuration HCOMC-eq)",
    )
    no_cooperation: bool = Field(
        False,
        description="HCOMC+ (an extension, not in the paper): add 'none' (VMC keeps car "
        "following, only VR's own merge is planned) to the cooperation modes HCOMC chooses from",
    )

    @field_validator("controller")
    @classmethod
    def _controller_name(cls, value: str) -> str:
        if not CONTROLLER_SPEC.fullmatch(value):
            raise ValueError(
                f"'{value}' is not a controller name; allowed: a registered name (none, hcomc, "
                "fifo, game, game-capped, or one an installed package registers), "
                "'package.module:Class' or 'path/to/file.py:Class'"
            )
        return value
