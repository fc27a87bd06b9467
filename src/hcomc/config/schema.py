"""The scenario schema: frozen pydantic v2 models, one per config table, with units and
defaults in each field's description; unknown keys are rejected (``extra="forbid"``)."""

from __future__ import annotations

import re
from itertools import pairwise
from typing import Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    field_validator,
    model_validator,
)

__all__ = [
    "CAVParams",
    "ConfigError",
    "ControlParams",
    "DemandParams",
    "HDVParams",
    "IDMParams",
    "LaneChangeParams",
    "PlatoonParams",
    "RoadParams",
    "ScenarioConfig",
]


MIN_STEP = 1e-3
"""Shortest simulation step [s] of the scenario and corridor engines."""

MIN_HEADWAY = 0.1
"""Shortest headway between two vehicles entering one lane [s]."""

CONTROLLER_SPEC = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+-]*|[^:\s][^:]*:[A-Za-z_][A-Za-z0-9_]*")
"""A controller name: a registered name, or ``module:Class`` / ``path/to/file.py:Class``."""


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class IDMParams(_Frozen):
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


class LaneChangeParams(_Frozen):
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
    cav_game: bool = Field(
        False,
        description="CAV discretionary changes accepted by MOBIL must also be the SV's "
        "equilibrium action of the Section III-B Stackelberg/Harsanyi game",
    )


class RoadParams(_Frozen):
    """Two-lane highway with an on-ramp and acceleration lane (paper Section II-A).

    Lane 2 (outer) has its centre at y = +W, lane 1 at y = 0, the ramp and acceleration lane
    at y = -W. The ramp runs parallel to lane 1 from ``ramp_start``; merging is allowed on
    the acceleration lane ``[accel_lane_start, accel_lane_end]``, which ends there.
    """

    length: float = Field(1500.0, gt=100, le=1_000_000, description="mainline length [m]")
    lane_width: float = Field(3.75, gt=2, le=6, description="W, lane width [m]")
    accel_lane_start: float = Field(700.0, ge=0, description="start of the acceleration lane [m]")
    accel_lane_end: float = Field(950.0, gt=0, description="end of the acceleration lane [m]")
    ramp_start: float = Field(250.0, ge=0, description="where ramp vehicles enter [m]")
    control_zone_length: float = Field(
        300.0, ge=0, description="cooperative control zone upstream of the acceleration lane [m]"
    )
    vehicle_length: float = Field(5.0, gt=1, le=25, description="vehicle length [m]")
    vehicle_width: float = Field(1.8, gt=0.5, le=3, description="vehicle width [m]")

    @model_validator(mode="after")
    def _ordered(self) -> RoadParams:
        if not self.ramp_start < self.accel_lane_start < self.accel_lane_end < self.length:
            raise ValueError(
                "need ramp_start < accel_lane_start < accel_lane_end < length, got "
                f"{self.ramp_start} < {self.accel_lane_start} < {self.accel_lane_end} "
                f"< {self.length}"
            )
        return self

    @property
    def control_zone_start(self) -> float:
        """Upstream end of the cooperative control zone [m]."""
        return max(0.0, self.accel_lane_start - self.control_zone_length)


class DemandParams(_Frozen):
    """Traffic demand: headways per lane, CAV share, insertion speeds (paper Table I).

    ``pattern = "random"``: headways are ``min_headway + Exp(mean - min_headway)``, so the
    mean is exactly the condition's average time headway, and each vehicle is a CAV with
    probability ``cav_penetration``. ``pattern = "uniform"`` (the deterministic paper
    scenario): every headway equals the mean and CAVs are spread evenly with the exact
    share. The ramp either releases one key merging vehicle (``ramp = "single"``, the
    paper's setting) or a continuous flow. Mainline vehicles enter at ``main_speed``: a
    fixed speed [m/s], or ``"equilibrium"``, the lane's IDM steady-state speed for its
    mean headway (see :mod:`hcomc.sim.demand`).
    """

    mean_headway_main_1: float = Field(5.0, gt=0, le=3600, description="lane 1 mean headway [s]")
    mean_headway_main_2: float = Field(5.0, gt=0, le=3600, description="lane 2 mean headway [s]")
    min_headway: float = Field(
        1.0, ge=MIN_HEADWAY, le=60, description="minimum (shift) headway [s]"
    )
    cav_penetration: float = Field(0.9, ge=0, le=1, description="share of CAVs [-]")
    main_speed: float | Literal["equilibrium"] = Field(
        "equilibrium",
        description="mainline insertion speed: a fixed speed [m/s] (0 < v <= 70) or "
        "'equilibrium' (each lane's IDM steady state for its mean headway)",
    )
    pattern: Literal["random", "uniform"] = Field(
        "random",
        description="'random' = shifted exponential headways and random CAV assignment; "
        "'uniform' = every headway equal to the mean, CAVs spread evenly (no randomness)",
    )
    ramp: Literal["single", "flow", "none"] = Field(
        "single", description="'single' key merge, 'flow' continuous ramp demand, 'none'"
    )
    ramp_entry_time: float = Field(
        5.0, ge=0, description="'single': release time after warm-up [s]"
    )
    ramp_mean_headway: float = Field(20.0, gt=0, le=3600, description="'flow': ramp headway [s]")
    ramp_speed: float = Field(22.0, gt=0, le=70, description="insertion speed, ramp [m/s]")

    @field_validator("main_speed", mode="before")
    @classmethod
    def _main_speed(cls, value: Any) -> Any:
        if value == "equilibrium":
            return value
        if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value <= 70:
            raise ValueError("allowed: a speed in (0, 70] m/s or 'equilibrium'")
        return value

    @model_validator(mode="after")
    def _headways(self) -> DemandParams:
        for key in ("mean_headway_main_1", "mean_headway_main_2", "ramp_mean_headway"):
            value = getattr(self, key)
            if value <= self.min_headway:
                raise ValueError(
                    f"{key} = {value} must be greater than min_headway = {self.min_headway}"
                )
        return self


class PlatoonParams(_Frozen):
    """Scripted-leader platoon on one lane (car-following and string-stability studies).

    The leader follows the piecewise-linear speed profile through ``profile`` points
    ``[[t0, v0], [t1, v1], ...]`` (time [s], speed [m/s]); K followers of one kind start at
    their equilibrium gap behind it.
    """

    followers: int = Field(10, ge=1, le=100_000, description="K, number of followers")
    kind: Literal["hdv", "cav"] = Field("hdv", description="follower kind")
    initial_speed: float = Field(25.0, ge=0, le=70, description="initial speed [m/s]")
    profile: list[tuple[float, float]] = Field(
        default_factory=lambda: [
            (0.0, 25.0),
            (10.0, 25.0),
            (15.0, 15.0),
            (40.0, 15.0),
            (50.0, 25.0),
        ],
        max_length=10_000,
        description="leader speed profile points (t [s], v [m/s]), linear in between",
    )

    @model_validator(mode="after")
    def _profile(self) -> PlatoonParams:
        times = [p[0] for p in self.profile]
        if len(times) < 1 or any(b <= a for a, b in pairwise(times)):
            raise ValueError(f"profile times must be strictly increasing, got {times}")
        if any(p[1] < 0 for p in self.profile):
            raise ValueError("profile speeds must be >= 0")
        return self


class ControlParams(_Frozen):
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
            "through pymoo (identical results, slower); 'pso' / 'pso-pymoo' likewise for PSO; "
            "'sa' = simulated annealing, 'sa-scipy' = the same through SciPy's dual_annealing "
            "(identical results, slower)"
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
        1.0,
        ge=0,
        le=60,
        description="receding horizon: re-identify the key vehicles and replan every this many "
        "seconds until VR starts its lane change; 0 = plan once at control-zone entry [s]",
    )
    commitment_margin: float = Field(
        0.2,
        ge=0,
        le=2,
        description="HCOMC replanning keeps the live plan's cooperating vehicle, mode and "
        "sequence unless the best new plan's Eq. 19 cost (min-max normalised over the new "
        "Pareto set, range 0-2) is lower by more than this; 0 = always take the best [-]",
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


class ScenarioConfig(_Frozen):
    """A complete, resolved scenario: road, demand, vehicle models and run control."""

    name: str = Field("custom", description="scenario name")
    description: str = Field("", description="free text")
    scenario: Literal["merge", "platoon"] = Field("merge", description="scenario type")
    seed: int = Field(0, ge=0, description="default random seed (the CLI --seed overrides it)")
    dt: float = Field(0.1, ge=MIN_STEP, le=1, description="simulation step [s]")
    duration: float = Field(90.0, gt=0, le=86_400, description="measured duration [s]")
    warmup: float = Field(30.0, ge=0, le=3600, description="unlogged warm-up before t = 0 [s]")
    log_interval: float = Field(0.1, gt=0, le=60, description="logging interval [s]")
    log_memory_limit: float = Field(
        8.0,
        gt=0,
        le=1024,
        description=(
            "a run whose log or perception history would need more memory than this is "
            "refused before anything is allocated, or stopped when its log must grow beyond "
            "it [GiB]"
        ),
    )
    road: RoadParams = Field(default_factory=RoadParams)
    demand: DemandParams = Field(default_factory=DemandParams)
    hdv: HDVParams = Field(default_factory=HDVParams)
    cav: CAVParams = Field(default_factory=CAVParams)
    lane_change: LaneChangeParams = Field(default_factory=LaneChangeParams)
    platoon: PlatoonParams = Field(default_factory=PlatoonParams)
    control: ControlParams = Field(default_factory=ControlParams)

    @model_validator(mode="after")
    def _steps(self) -> ScenarioConfig:
        ratio = self.log_interval / self.dt
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"log_interval = {self.log_interval} must be a positive multiple of dt = {self.dt}"
            )
        return self

    @model_validator(mode="after")
    def _memory(self) -> ScenarioConfig:
        need = self.history_gib()
        if need > self.log_memory_limit:
            raise ValueError(
                f"the HDV perception history of this run would need {need:.3g} GiB "
                f"(dt = {self.dt} s, {self.expected_vehicles():.3g} vehicles expected), more "
                f"than log_memory_limit = {self.log_memory_limit} GiB; allowed: a larger dt, "
                "a shorter duration or sparser demand"
            )
        return self

    def expected_vehicles(self) -> float:
        """Vehicles a run is expected to release: its followers (platoon) or every lane's
        demand over warm-up and duration at its mean headway."""
        if self.scenario == "platoon":
            return self.platoon.followers + 1.0
        total = self.warmup + self.duration
        d = self.demand
        rate = 1.0 / d.mean_headway_main_1 + 1.0 / d.mean_headway_main_2
        rate += 1.0 / d.ramp_mean_headway if d.ramp == "flow" else 0.0
        return total * rate + 1.0

    def history_gib(self) -> float:
        """Memory of the perception ring buffer (x and v of every vehicle over the longest
        reaction delay, :class:`hcomc.sim.perception.Perception`) [GiB], estimated from
        :meth:`expected_vehicles` before anything is allocated."""
        h = self.hdv
        rows = max(h.reaction_time_gap, h.reaction_time_speed, h.reaction_time_approach)
        rows = rows / self.dt + 2.0
        return 2 * 8 * rows * self.expected_vehicles() / 2**30


class ConfigError(ValueError):
    """A config could not be read or validated; the message names key, value and rule."""
