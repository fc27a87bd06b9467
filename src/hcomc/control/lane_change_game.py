r"""Discretionary lane-change decision as a Stackelberg-Harsanyi game (paper Section III-B).

The subject vehicle SV (a CAV with the intention to change to the adjacent lane) is the
Stackelberg leader; the follower FV in the target lane is the follower player (MODELS.md §9):

* SV actions :math:`A_{SV} = \{LC, K\}` (indices 0, 1): change lane / keep following.
* FV actions :math:`A_{FV} = \{LC, CS, AC, DC\}` (indices 0-3): change lane, constant speed,
  accelerate (:math:`+a_{FV}`), decelerate (:math:`-a_{FV}`), with :math:`a_{FV}` =
  :attr:`GameParams.fv_accel`.
* An HDV follower's driving style is a Harsanyi type θ ∈ {aggressive, normal, conservative}
  with prior :math:`p_\theta`; SV minimises its expected cost under the induced mixed strategy
  (:func:`hcomc.control.game.solve_stackelberg_harsanyi`). A CAV follower's type is known and
  it cooperates (:func:`hcomc.control.game.solve_cooperative`, with the "normal" weights).

Every joint action is simulated over the horizon :math:`H = T_{lc}` on the grid
:math:`t_k = k\,\Delta t`, :math:`k = 1..N`, and scored with the cost of MODELS.md §9,

.. math:: J = w_s J_s + w_e J_e + w_c J_c,

each term normalised to about [0, 1]:

* safety :math:`J_s = \min(1, a_{cr}/a_{th})` with :math:`a_{cr}` the worst critical
  acceleration (paper Eq. 15, :func:`hcomc.safety.critical.critical_acceleration`) over the
  relevant follower/leader pairs and the horizon, :math:`a_{th}` =
  :attr:`GameParams.safety_threshold`; :math:`J_s = 10` (effectively forbidding) when a gap is
  :math:`\le 0` (overlap) or the required deceleration is infeasible (:math:`a_{cr} = \infty`,
  or :math:`a_{cr} > a_{merg}`, the emergency deceleration, which the follower cannot exceed);
* efficiency :math:`J_e = \operatorname{mean}_k |v_k - v_0| / v_0`;
* comfort :math:`J_c = \max_k |\mathbf j_k| / j_{max} + \operatorname{mean}_k
  \left[(a_{x,k}/a_{ref,k})^2 + (a_{y,k}/a_{max})^2\right]`, with the jerk from finite
  differences of the acceleration series (starting from acceleration 0), vector norms over the
  longitudinal and lateral components, :math:`a_{ref} = a_{max}` for :math:`a_x \ge 0` and the
  comfortable deceleration :math:`b` for :math:`a_x < 0`.

Assumptions (the paper gives no weights, priors or payoff formulas; reference [20] of the paper,
which defines them, is only known by its abstract):

* Types, IDM parameters, cost weights and prior are the *suggested* values of MODELS.md §9,
  not the paper's; they are configurable in :class:`GameParams`.
* Leaders (SV's current leader and the target-lane leader) keep constant speed.
* SV keeping (K) follows its current leader with the IDM (Eq. 1); SV changing (LC) follows the
  target-lane leader with the IDM, blended from the acceleration towards its old leader with the
  tanh transition of Eq. 14 (duration H), and moves laterally along the rest-to-rest quintic of
  Eq. 4 over H (lane width :attr:`GameParams.lane_width`). The lateral quintic is what makes a
  lane change cost something in comfort: without a gain, K is preferred (it plays the role of
  MOBIL's changing threshold).
* FV actions are constant accelerations (closed-form kinematics, speed floored at 0).
* FV LC ("moves away to the other lane") is modelled as FV cruising at constant speed, moving
  laterally along the same quintic, and ceasing to interact with SV once it has crossed the lane
  boundary at the lateral midpoint :math:`H/2`. Before that it is still in the target lane, so
  if SV changes lane the FV-behind-SV pair counts for :math:`t_k \le H/2` (for both players).
  After :math:`H/2` FV is scored behind the target-lane leader as a proxy for the unknown leader
  in the lane it moves to. (Treating FV LC as leaving instantly would give every follower a free
  escape from any cut-in, however dangerous.)
* FV safety uses its gap to SV when SV changes lane (SV is its new leader), otherwise its gap to
  the target-lane leader. SV safety is the worse of (SV behind its leader in the lane it ends
  in) and (FV behind SV, if SV changes lane). Eq. 15 uses the delay of the *follower's* kind
  (:attr:`GameParams.delay_cav` / :attr:`GameParams.delay_hdv`). An absent leader or follower
  contributes no pair.
* SV's cost does not depend on FV's type (FV's actions are type-independent constant
  accelerations); FV's cost does through the type's weights and its :math:`a_{max}`, :math:`b`.
  The type's time headway is carried (MODELS.md §9 table) but not used by the constant-
  acceleration actions.

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section III-B, Eqs. (1),
   (4), (14), (15).
.. [2] MODELS.md §5 (tanh transition), §7 (Eq. 15), §9 (game formulation).
.. [3] P. Hang et al., "Human-like decision making for autonomous driving: a noncooperative game
   theoretic approach", IEEE T-ITS 22(4), 2076-2087 (2021) (driving-style weighted costs).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from hcomc._typing import BoolArray, FloatArray
from hcomc.config import IDMParams
from hcomc.control.game import GameSolution, solve_cooperative, solve_stackelberg_harsanyi
from hcomc.models.idm import idm_acceleration, iidm_acceleration
from hcomc.models.quintic import quintic_shape
from hcomc.models.transition import blend_acceleration, transition_weight
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
    "LaneChangeDecision",
    "game_params",
    "game_vehicle",
    "lane_change_game",
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
    """A Harsanyi driver type (driving style) of the follower, MODELS.md §9.

    The IDM parameters and cost weights are MODELS.md §9's *suggestions*; the paper gives none.
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
"""Aggressive style (MODELS.md §9, suggested values)."""
NORMAL = DriverType(
    name="normal",
    time_headway=1.5,
    max_accel=1.4,
    comfort_decel=2.0,
    w_safety=0.4,
    w_efficiency=0.4,
    w_comfort=0.2,
)
"""Normal style (MODELS.md §9, suggested values)."""
CONSERVATIVE = DriverType(
    name="conservative",
    time_headway=2.0,
    max_accel=1.0,
    comfort_decel=1.5,
    w_safety=0.6,
    w_efficiency=0.2,
    w_comfort=0.2,
)
"""Conservative style (MODELS.md §9, suggested values)."""


class GameParams(_Frozen):
    """Parameters of the discretionary lane-change game (paper §III-B; MODELS.md §7, §9).

    The paper states none of the weights, priors or type parameters; the defaults are the
    MODELS.md §9 suggestions (prior 0.25/0.5/0.25, SV weights 0.5/0.3/0.2) and the Eq. 15
    defaults of MODELS.md §0. ``lane_width`` and ``transition_tolerance`` are additions used by
    the lateral comfort term and the Eq. 14 transition.
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
        4.0, gt=0, le=20, description="a_th, critical acceleration mapped to J_s = 1 [m/s^2]"
    )
    jerk_max: float = Field(5.0, gt=0, le=100, description="j_max, jerk normaliser [m/s^3]")
    delay_cav: float = Field(0.5, ge=0, le=5, description="Eq. 15 delay T, CAV follower [s]")
    delay_hdv: float = Field(1.0, ge=0, le=5, description="Eq. 15 delay T, HDV follower [s]")
    min_distance: float = Field(2.0, ge=0, le=50, description="Eq. 15 residual distance D [m]")
    emergency_decel: float = Field(
        7.5, gt=0, le=15, description="Eq. 15 a_merg, emergency deceleration [m/s^2]"
    )
    lane_width: float = Field(3.75, gt=0, le=10, description="W, lateral lane-change offset [m]")
    transition_tolerance: float = Field(
        0.01, gt=0, lt=0.5, description="epsilon of the Eq. 14 transition, Psi(0) = eps [-]"
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


"""Default game parameters (MODELS.md §9 suggestions)."""


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


@dataclass(frozen=True)
class LaneChangeDecision:
    """Outcome of :func:`lane_change_game`.

    Attributes
    ----------
    change : bool
        True if SV's equilibrium action is LC.
    solution : GameSolution
        The game solution (cooperative or Stackelberg-Harsanyi).
    sv_cost : numpy.ndarray
        SV cost matrix used, shape ``(2, F)`` (``F = 4``, or 1 without a follower).
    fv_cost : numpy.ndarray
        FV cost used: ``(2, 4, n_types)`` for an HDV follower, ``(2, 4)`` for a CAV follower
        (reference type), ``(2, 1, n_types)`` zeros without a follower.
    reason : str
        Short explanation of the solver used and the outcome.
    sv_safety : numpy.ndarray
        SV's safety cost J_s per joint action, shape ``(2, F)``.
    """

    change: bool
    solution: GameSolution
    sv_cost: FloatArray
    fv_cost: FloatArray
    reason: str
    sv_safety: FloatArray

    @property
    def change_is_safe(self) -> bool:
        """Whether SV's lane change keeps J_s < 1 (a_cr below the threshold) against every
        response FV plays with positive probability in the equilibrium."""
        support = self.solution.fv_mixed[SV_LC] > 0.0
        return bool(np.all(self.sv_safety[SV_LC][support] < 1.0))


def _leader_track(leader: GameVehicle | None, t: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Rear-bumper position (N,) [m] and speed (N,) [m/s] of a constant-speed leader at ``t``.

    An absent leader is at ``+inf`` with speed 0, so every gap to it is ``+inf`` (IDM free road,
    Eq. 15 gives 0).
    """
    if leader is None:
        return np.full(t.shape, np.inf), np.zeros(t.shape)
    rear = leader.x - leader.length + leader.v * t
    return rear, np.full(t.shape, float(leader.v))


def _car_following(idm: IDMParams, v0: float) -> Callable[..., FloatArray]:
    """IDM (or IIDM, per ``idm.variant``) acceleration as a function of (s, v, dv)."""
    kernel = iidm_acceleration if idm.variant == "iidm" else idm_acceleration

    def accel(s: FloatArray, v: FloatArray, dv: FloatArray) -> FloatArray:
        return kernel(
            s,
            v,
            dv,
            v0=v0,
            T=idm.time_headway,
            a=idm.max_accel,
            b=idm.comfort_decel,
            s0=idm.min_gap,
            delta=idm.exponent,
        )

    return accel


def _simulate_sv(
    sv: GameVehicle,
    old: GameVehicle | None,
    new: GameVehicle | None,
    idm: IDMParams,
    params: GameParams,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Positions, speeds and applied accelerations (2, N) of SV for actions (LC, K).

    Ballistic update with a stop at v = 0; the IDM output is floored at ``-emergency_decel``.
    Row LC blends the accelerations towards ``old`` and ``new`` with Eq. 14 (Ψ at the start of
    each step, τ = t_{k-1}); row K follows ``old``. The loop runs over the N time steps only.
    """
    n, dt = params.n_steps, params.dt
    t_start: FloatArray = dt * np.arange(n, dtype=np.float64)
    old_rear, old_v = _leader_track(old, t_start)
    new_rear, new_v = _leader_track(new, t_start)
    psi = transition_weight(t_start, params.horizon, params.transition_tolerance)
    weights = np.stack([psi, np.zeros(n)])  # (2, N): LC blends, K keeps a_ori
    accel = _car_following(idm, sv.desired_speed)

    x = np.full(2, float(sv.x))
    v = np.full(2, float(sv.v))
    xs, vs, acc = np.empty((2, n)), np.empty((2, n)), np.empty((2, n))
    for k in range(n):
        a_ori = accel(old_rear[k] - x, v, v - old_v[k])
        a_new = accel(new_rear[k] - x, v, v - new_v[k])
        a = np.maximum(blend_acceleration(a_ori, a_new, weights[:, k]), -params.emergency_decel)
        v_next = v + a * dt
        stops = v_next < 0.0
        dx = np.where(stops, v * v / (2.0 * np.where(stops, -a, 1.0)), v * dt + 0.5 * a * dt * dt)
        v_next = np.maximum(v_next, 0.0)
        acc[:, k] = (v_next - v) / dt
        x = x + dx
        v = v_next
        xs[:, k], vs[:, k] = x, v
    return xs, vs, acc


def _fv_kinematics(
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


def _lateral_accel(t: FloatArray, params: GameParams) -> FloatArray:
    """Lateral acceleration (N,) of a rest-to-rest quintic lane change over H (Eq. 4) [m/s^2]."""
    _, _, ddp = quintic_shape(t / params.horizon)
    return params.lane_width / params.horizon**2 * ddp


def _safety_cost(
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


def _efficiency_cost(v: FloatArray, v0: float) -> FloatArray:
    """J_e = mean over the last axis of |v - v0| / v0 [-]."""
    return np.asarray(np.mean(np.abs(v - v0), axis=-1) / v0, dtype=np.float64)


def _comfort_cost(
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


def lane_change_game(
    sv: GameVehicle,
    fv: GameVehicle | None,
    sv_leader: GameVehicle | None,
    target_leader: GameVehicle | None,
    *,
    params: GameParams = GAME_DEFAULT,
    sv_idm: IDMParams,
    fv_idm: IDMParams,
) -> LaneChangeDecision:
    r"""Decide a discretionary lane change of SV by the SV-FV game (paper §III-B; MODELS §9).

    Builds the cost matrices of every joint action (SV ∈ {LC, K}, FV ∈ {LC, CS, AC, DC}) by
    forward simulation over the horizon (see the module docstring for the dynamics, the cost
    terms and all assumptions) and solves the game:

    * no follower in the target lane: SV compares LC and K alone (one dummy FV action, FV cost
      zero);
    * HDV follower: :func:`~hcomc.control.game.solve_stackelberg_harsanyi` with
      :attr:`GameParams.prior` over :attr:`GameParams.types`;
    * CAV follower: :func:`~hcomc.control.game.solve_cooperative`, FV cost with the weights of
      the "normal" type (:attr:`GameParams.reference_type`) and the follower's own ``fv_idm``
      acceleration limits (its parameters are known, no type uncertainty).

    Parameters
    ----------
    sv : GameVehicle
        Subject vehicle (normally a CAV) that considers changing lane.
    fv : GameVehicle or None
        Follower in the target lane (behind SV's target slot); None if absent. A follower that
        is not behind SV gives a gap ``<= 0`` and forbids LC.
    sv_leader : GameVehicle or None
        SV's current leader (constant speed); None for a free road.
    target_leader : GameVehicle or None
        Leader in the target lane (constant speed); None for a free target lane.
    params : GameParams, optional
        Game parameters; default :data:`GAME_DEFAULT`.
    sv_idm : IDMParams
        SV's car-following parameters (Eq. 1; ``variant`` selects IDM or IIDM). The desired
        speed is taken from ``sv.desired_speed``.
    fv_idm : IDMParams
        FV's car-following parameters; its ``max_accel``/``comfort_decel`` normalise a CAV
        follower's comfort cost. For an HDV follower the types' values are used instead.

    Returns
    -------
    LaneChangeDecision
        ``change`` is True if SV's equilibrium action is LC (index :data:`SV_LC`).

    Notes
    -----
    Pure: inputs are not modified; the result depends only on the arguments.
    """
    n = params.n_steps
    # evaluation grid t_k = k dt, k = 1..N
    t: FloatArray = params.dt * np.arange(1, n + 1, dtype=np.float64)
    lat = _lateral_accel(t, params)
    sv_delay = params.delay_cav if sv.is_cav else params.delay_hdv

    sv_x, sv_v, sv_a = _simulate_sv(sv, sv_leader, target_leader, sv_idm, params)
    sv_rear = sv_x - sv.length
    old_rear, old_v = _leader_track(sv_leader, t)
    tl_rear, tl_v = _leader_track(target_leader, t)

    # SV behind its leader in the lane it ends in: target leader (LC), current leader (K).
    lead_rear = np.stack([tl_rear, old_rear])
    lead_v = np.stack([tl_v, old_v])
    all_on = np.ones((2, n), dtype=bool)
    sv_js_lead = _safety_cost(lead_rear - sv_x, sv_v, lead_v, sv_delay, all_on, params)  # (2,)
    sv_je = _efficiency_cost(sv_v, sv.desired_speed)  # (2,)
    sv_lat = np.stack([lat, np.zeros(n)])
    sv_jc = _comfort_cost(sv_a, sv_lat, sv_idm.max_accel, sv_idm.comfort_decel, params)  # (2,)
    w_s, w_e, w_c = params.sv_weights

    if fv is None:
        sv_cost = (w_s * sv_js_lead + w_e * sv_je + w_c * sv_jc)[:, None]  # (2, 1)
        fv_cost = np.zeros((2, 1, len(params.types)))
        solution = solve_stackelberg_harsanyi(sv_cost, fv_cost, params.prior)
        return _decision(
            solution, sv_cost, fv_cost, sv_js_lead[:, None], "no follower in target lane"
        )

    fv_delay = params.delay_cav if fv.is_cav else params.delay_hdv
    fv_x, fv_v, fv_a = _fv_kinematics(fv, t, params)  # (4, N)
    # FV interacts with SV (if SV changes) throughout, except after its own LC midpoint H/2.
    with_sv = np.ones((4, n), dtype=bool)
    with_sv[FV_LC] = t <= 0.5 * params.horizon + 1e-9
    gap_sv = sv_rear[SV_LC][None, :] - fv_x  # (4, N): FV behind SV in the target lane
    v_sv_lc = np.broadcast_to(sv_v[SV_LC], (4, n))
    sv_js_fv = _safety_cost(gap_sv, fv_v, v_sv_lc, fv_delay, with_sv, params)  # (4,)
    sv_js = np.maximum(sv_js_lead[:, None], np.stack([sv_js_fv, np.zeros(4)]))  # (2, 4)
    sv_cost = w_s * sv_js + (w_e * sv_je + w_c * sv_jc)[:, None]  # (2, 4)

    # FV's leader: SV if SV changes (while FV is still in the lane), else the target leader.
    gap_tl = tl_rear[None, :] - fv_x  # (4, N)
    fv_gap = np.stack([np.where(with_sv, gap_sv, gap_tl), gap_tl])  # (2, 4, N)
    fv_lead_v = np.stack([np.where(with_sv, v_sv_lc, tl_v), np.broadcast_to(tl_v, (4, n))])
    fv_js = _safety_cost(fv_gap, fv_v, fv_lead_v, fv_delay, np.ones_like(fv_gap, bool), params)
    fv_je = _efficiency_cost(fv_v, fv.desired_speed)  # (4,)
    fv_lat = np.zeros((4, n))
    fv_lat[FV_LC] = lat

    if fv.is_cav:
        ref = params.types[params.reference_type]
        fv_jc = _comfort_cost(fv_a, fv_lat, fv_idm.max_accel, fv_idm.comfort_decel, params)
        fv_cost = ref.w_safety * fv_js + ref.w_efficiency * fv_je + ref.w_comfort * fv_jc
        solution = solve_cooperative(sv_cost, fv_cost)
        return _decision(
            solution, sv_cost, fv_cost, sv_js, "CAV follower: cooperative joint minimum"
        )

    a_max = np.array([ty.max_accel for ty in params.types])
    b_comf = np.array([ty.comfort_decel for ty in params.types])
    fv_jc = _comfort_cost(fv_a[:, None, :], fv_lat[:, None, :], a_max, b_comf, params)  # (4, T)
    w = np.array([[ty.w_safety, ty.w_efficiency, ty.w_comfort] for ty in params.types])
    fv_cost = (
        w[:, 0] * fv_js[:, :, None] + w[:, 1] * fv_je[None, :, None] + w[:, 2] * fv_jc[None]
    )  # (2, 4, n_types)
    solution = solve_stackelberg_harsanyi(sv_cost, fv_cost, params.prior)
    return _decision(
        solution, sv_cost, fv_cost, sv_js, "HDV follower: Stackelberg-Harsanyi equilibrium"
    )


def _decision(
    solution: GameSolution,
    sv_cost: FloatArray,
    fv_cost: FloatArray,
    sv_safety: FloatArray,
    context: str,
) -> LaneChangeDecision:
    """Wrap a solution with its cost matrices and a one-line reason."""
    change = solution.sv_action == SV_LC
    e_lc, e_k = solution.expected_cost[SV_LC], solution.expected_cost[SV_K]
    verdict = "change lane" if change else "keep lane"
    reason = f"{context}; {verdict} (cost LC {e_lc:.3f} vs K {e_k:.3f})"
    return LaneChangeDecision(
        change=change,
        solution=solution,
        sv_cost=sv_cost,
        fv_cost=fv_cost,
        reason=reason,
        sv_safety=sv_safety,
    )
