r"""Discretionary lane-change decision as a Stackelberg-Harsanyi game (paper Section III-B).

The subject vehicle SV (a CAV with the intention to change to the adjacent lane) is the
Stackelberg leader; the follower FV in the target lane is the follower player:

* SV actions :math:`A_{SV} = \{LC, K\}` (indices 0, 1): change lane / keep following.
* FV actions :math:`A_{FV} = \{LC, CS, AC, DC\}` (indices 0-3): change lane, constant speed,
  accelerate (:math:`+a_{FV}`), decelerate (:math:`-a_{FV}`), with :math:`a_{FV}` =
  :attr:`GameParams.fv_accel`.
* An HDV follower's driving style is a Harsanyi type θ ∈ {aggressive, normal, conservative}
  with prior :math:`p_\theta`; SV minimises its expected cost under the induced mixed strategy
  (:func:`~hcomc.control.lane_change_game.solvers.solve_stackelberg_harsanyi`). A CAV
  follower's type is known and it cooperates
  (:func:`~hcomc.control.lane_change_game.solvers.solve_cooperative`, with the "normal" weights).

Every joint action is simulated over the horizon :math:`H = T_{lc}` on the grid
:math:`t_k = k\,\Delta t`, :math:`k = 1..N`, and scored with the cost of docs/models.md,

.. math:: J = w_s J_s + w_e J_e + w_c J_c,

each term normalised to about [0, 1]:

* safety :math:`J_s = a_{cr}/a_{merg}`, the safety term shared with the merge game
  (:func:`hcomc.control.lane_change_game.game_safety.safety_term`: linear, not capped), with
  :math:`a_{cr}` the worst critical acceleration (paper Eq. 15,
  :func:`hcomc.equations.safety.critical_acceleration`) over the relevant follower/leader pairs
  and the horizon and :math:`a_{merg}` = :attr:`GameParams.emergency_decel`; :math:`J_s = 10`
  (effectively forbidding) when a gap is :math:`\le 0` (overlap) or the required deceleration
  is infeasible (:math:`a_{cr} = \infty`, or :math:`a_{cr} > a_{merg}`, the emergency
  deceleration, which the follower cannot exceed), so a feasible action has
  :math:`J_s \le 1`;
* efficiency :math:`J_e = \operatorname{mean}_k |v_k - v_0| / v_0`;
* comfort :math:`J_c = \max_k |\mathbf j_k| / j_{max} + \operatorname{mean}_k
  \left[(a_{x,k}/a_{ref,k})^2 + (a_{y,k}/a_{max})^2\right]`, with the jerk from finite
  differences of the acceleration series (starting from acceleration 0), vector norms over the
  longitudinal and lateral components, :math:`a_{ref} = a_{max}` for :math:`a_x \ge 0` and the
  comfortable deceleration :math:`b` for :math:`a_x < 0`.

Assumptions (the paper gives no weights, priors or payoff formulas; reference [20] of the paper,
which defines them, is only known by its abstract):

* Types, IDM parameters, cost weights and prior are the *suggested* values of docs/models.md,
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
  The type's time headway is carried but not used by the constant-
  acceleration actions.

The game decides as the paper says (Section III-B: "SV takes the minimization of the
expectation of its own payoff functions as the optimal strategy"): ``change`` of the
:class:`LaneChangeDecision` is SV's equilibrium action. HCOMC's lateral cooperation is also
admitted by a rule *added* to the paper (an extension, docs/models.md): SV's change keeps
:math:`a_{cr}` below :attr:`GameParams.safety_threshold` against every response FV plays with
positive probability (``change_is_safe``). The decision records which of the two admitted a
change (``admitted_by``: "equilibrium", "safety_rule" or "").

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section III-B, Eqs. (1),
   (4), (14), (15).
.. [2] docs/models.md: Eq. 14, Eq. 15, the lane-change game.
.. [3] P. Hang et al., "Human-like decision making for autonomous driving: a noncooperative game
   theoretic approach", IEEE T-ITS 22(4), 2076-2087 (2021) (driving-style weighted costs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hcomc._typing import FloatArray
from hcomc.config import IDMParams
from hcomc.control.lane_change_game import game_safety
from hcomc.control.lane_change_game.costs import (
    INFEASIBLE_SAFETY_COST,
    comfort_cost,
    efficiency_cost,
    safety_cost,
    worst_critical_acceleration,
)
from hcomc.control.lane_change_game.params import (
    FV_AC,
    FV_ACTIONS,
    FV_CS,
    FV_DC,
    FV_LC,
    GAME_DEFAULT,
    SV_ACTIONS,
    SV_K,
    SV_LC,
    DriverType,
    GameParams,
    game_params,
)
from hcomc.control.lane_change_game.players import (
    GameVehicle,
    fv_kinematics,
    game_vehicle,
    lateral_accel,
    leader_track,
    simulate_sv,
)
from hcomc.control.lane_change_game.solvers import (
    GameSolution,
    solve_cooperative,
    solve_stackelberg_harsanyi,
)

__all__ = [
    "ADMITTED_BY",
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


ADMITTED_BY: tuple[str, ...] = ("equilibrium", "safety_rule", "")
"""Values of :attr:`LaneChangeDecision.admitted_by`: SV's change admitted by the game's
equilibrium (the paper's rule), by the added safety rule alone (an extension), or not at
all."""


@dataclass(frozen=True)
class LaneChangeDecision:
    """Outcome of :func:`lane_change_game`: the equilibrium and how a change was admitted.

    Attributes
    ----------
    change : bool
        True if SV's *equilibrium* action is LC (paper §III-B: SV minimises its expected
        cost). The engine's CAV discretionary changes go by this alone.
    solution : GameSolution
        The game solution (cooperative or Stackelberg-Harsanyi).
    sv_cost : numpy.ndarray
        SV cost matrix used, shape ``(2, F)`` (``F = 4``, or 1 without a follower).
    fv_cost : numpy.ndarray
        FV cost used: ``(2, 4, n_types)`` for an HDV follower, ``(2, 4)`` for a CAV follower
        (reference type), ``(2, 1, n_types)`` zeros without a follower.
    reason : str
        Short explanation of the solver used, the outcome and how a change was admitted.
    sv_safety : numpy.ndarray
        SV's safety cost J_s = a_cr / a_merg per joint action, shape ``(2, F)`` (the shared
        term, :func:`hcomc.control.lane_change_game.game_safety.safety_term`).
    sv_critical_accel : numpy.ndarray
        SV's worst Eq. 15 a_cr [m/s^2] per joint action (the worse of SV behind its leader and
        FV behind SV), shape ``(2, F)``; ``inf`` for an infeasible action.
    safety_threshold : float
        a_th [m/s^2] of the added safety rule (:attr:`GameParams.safety_threshold`).
    change_is_safe : bool
        The added safety rule (an extension, not the paper's): SV's change keeps
        ``sv_critical_accel < safety_threshold`` against every response FV plays with positive
        probability in the equilibrium.
    admitted_by : str
        How a change of SV is admitted (one of :data:`ADMITTED_BY`): ``"equilibrium"`` when
        ``change`` (whatever the safety rule says), ``"safety_rule"`` when only the added rule
        admits it (``change_is_safe`` and not ``change``), ``""`` when neither does.
    """

    change: bool
    solution: GameSolution
    sv_cost: FloatArray
    fv_cost: FloatArray
    reason: str
    sv_safety: FloatArray
    sv_critical_accel: FloatArray
    safety_threshold: float
    change_is_safe: bool
    admitted_by: str

    def admits(self, safety_rule: bool = True) -> bool:
        """Whether SV's change is admitted: HCOMC's gate of lateral cooperation. By the
        equilibrium (``change``, the paper's game) or, with ``safety_rule`` (the extension,
        ``control.lateral_safety_rule``), by the added safety rule (``change_is_safe``)."""
        return self.change or (safety_rule and self.change_is_safe)


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
    r"""Decide a discretionary lane change of SV by the SV-FV game (paper §III-B).

    Builds the cost matrices of every joint action (SV ∈ {LC, K}, FV ∈ {LC, CS, AC, DC}) by
    forward simulation over the horizon (see the module docstring for the dynamics, the cost
    terms and all assumptions) and solves the game:

    * no follower in the target lane: SV compares LC and K alone (one dummy FV action, FV cost
      zero);
    * HDV follower: :func:`~hcomc.control.lane_change_game.solvers.solve_stackelberg_harsanyi` with
      :attr:`GameParams.prior` over :attr:`GameParams.types`;
    * CAV follower: :func:`~hcomc.control.lane_change_game.solvers.solve_cooperative`, FV
      cost with the weights of the "normal" type (:attr:`GameParams.reference_type`) and the
      follower's own ``fv_idm`` acceleration limits (its parameters are known, no type uncertainty).

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
    lat = lateral_accel(t, params)
    sv_delay = params.delay_cav if sv.is_cav else params.delay_hdv

    sv_x, sv_v, sv_a = simulate_sv(sv, sv_leader, target_leader, sv_idm, params)
    sv_rear = sv_x - sv.length
    old_rear, old_v = leader_track(sv_leader, t)
    tl_rear, tl_v = leader_track(target_leader, t)

    # SV behind its leader in the lane it ends in: target leader (LC), current leader (K).
    lead_rear = np.stack([tl_rear, old_rear])
    lead_v = np.stack([tl_v, old_v])
    all_on = np.ones((2, n), dtype=bool)
    sv_acr_lead = worst_critical_acceleration(
        lead_rear - sv_x, sv_v, lead_v, sv_delay, all_on, params
    )  # (2,)
    sv_je = efficiency_cost(sv_v, sv.desired_speed)  # (2,)
    sv_lat = np.stack([lat, np.zeros(n)])
    sv_jc = comfort_cost(sv_a, sv_lat, sv_idm.max_accel, sv_idm.comfort_decel, params)  # (2,)
    w_s, w_e, w_c = params.sv_weights

    if fv is None:
        sv_js = game_safety.safety_term(sv_acr_lead[:, None], params.emergency_decel)  # (2, 1)
        sv_cost = w_s * sv_js + (w_e * sv_je + w_c * sv_jc)[:, None]  # (2, 1)
        fv_cost = np.zeros((2, 1, len(params.types)))
        solution = solve_stackelberg_harsanyi(sv_cost, fv_cost, params.prior)
        return _decision(
            solution, sv_cost, fv_cost, sv_js, sv_acr_lead[:, None], params,
            "no follower in target lane",
        )  # fmt: skip

    fv_delay = params.delay_cav if fv.is_cav else params.delay_hdv
    fv_x, fv_v, fv_a = fv_kinematics(fv, t, params)  # (4, N)
    # FV interacts with SV (if SV changes) throughout, except after its own LC midpoint H/2.
    with_sv = np.ones((4, n), dtype=bool)
    with_sv[FV_LC] = t <= 0.5 * params.horizon + 1e-9
    gap_sv = sv_rear[SV_LC][None, :] - fv_x  # (4, N): FV behind SV in the target lane
    v_sv_lc = np.broadcast_to(sv_v[SV_LC], (4, n))
    sv_acr_fv = worst_critical_acceleration(gap_sv, fv_v, v_sv_lc, fv_delay, with_sv, params)
    sv_acr = np.maximum(sv_acr_lead[:, None], np.stack([sv_acr_fv, np.zeros(4)]))  # (2, 4)
    sv_js = game_safety.safety_term(sv_acr, params.emergency_decel)  # J_s is increasing in a_cr
    sv_cost = w_s * sv_js + (w_e * sv_je + w_c * sv_jc)[:, None]  # (2, 4)

    # FV's leader: SV if SV changes (while FV is still in the lane), else the target leader.
    gap_tl = tl_rear[None, :] - fv_x  # (4, N)
    fv_gap = np.stack([np.where(with_sv, gap_sv, gap_tl), gap_tl])  # (2, 4, N)
    fv_lead_v = np.stack([np.where(with_sv, v_sv_lc, tl_v), np.broadcast_to(tl_v, (4, n))])
    fv_js = safety_cost(fv_gap, fv_v, fv_lead_v, fv_delay, np.ones_like(fv_gap, bool), params)
    fv_je = efficiency_cost(fv_v, fv.desired_speed)  # (4,)
    fv_lat = np.zeros((4, n))
    fv_lat[FV_LC] = lat

    if fv.is_cav:
        ref = params.types[params.reference_type]
        fv_jc = comfort_cost(fv_a, fv_lat, fv_idm.max_accel, fv_idm.comfort_decel, params)
        fv_cost = ref.w_safety * fv_js + ref.w_efficiency * fv_je + ref.w_comfort * fv_jc
        solution = solve_cooperative(sv_cost, fv_cost)
        return _decision(
            solution, sv_cost, fv_cost, sv_js, sv_acr, params,
            "CAV follower: cooperative joint minimum",
        )  # fmt: skip

    a_max = np.array([ty.max_accel for ty in params.types])
    b_comf = np.array([ty.comfort_decel for ty in params.types])
    fv_jc = comfort_cost(fv_a[:, None, :], fv_lat[:, None, :], a_max, b_comf, params)  # (4, T)
    w = np.array([[ty.w_safety, ty.w_efficiency, ty.w_comfort] for ty in params.types])
    fv_cost = (
        w[:, 0] * fv_js[:, :, None] + w[:, 1] * fv_je[None, :, None] + w[:, 2] * fv_jc[None]
    )  # (2, 4, n_types)
    solution = solve_stackelberg_harsanyi(sv_cost, fv_cost, params.prior)
    return _decision(
        solution, sv_cost, fv_cost, sv_js, sv_acr, params,
        "HDV follower: Stackelberg-Harsanyi equilibrium",
    )  # fmt: skip


def _decision(
    solution: GameSolution,
    sv_cost: FloatArray,
    fv_cost: FloatArray,
    sv_safety: FloatArray,
    sv_critical_accel: FloatArray,
    params: GameParams,
    context: str,
) -> LaneChangeDecision:
    """Wrap a solution with its cost matrices, the added safety rule's verdict, how a change
    is admitted and a one-line reason."""
    change = solution.sv_action == SV_LC
    support = solution.fv_mixed[SV_LC] > 0.0
    worst = float(sv_critical_accel[SV_LC][support].max())
    change_is_safe = bool(worst < params.safety_threshold)
    admitted_by = "equilibrium" if change else "safety_rule" if change_is_safe else ""
    e_lc, e_k = solution.expected_cost[SV_LC], solution.expected_cost[SV_K]
    verdict = "change lane" if change else "keep lane"
    admission = {
        "equilibrium": "change admitted by the equilibrium",
        "safety_rule": "change admitted only by the added safety rule (extension)",
        "": "change not admitted",
    }[admitted_by]
    reason = (
        f"{context}; {verdict} (cost LC {e_lc:.3f} vs K {e_k:.3f}); {admission} "
        f"(worst a_cr of LC {worst:.2f} vs threshold {params.safety_threshold:g} m/s^2)"
    )
    return LaneChangeDecision(
        change=change,
        solution=solution,
        sv_cost=sv_cost,
        fv_cost=fv_cost,
        reason=reason,
        sv_safety=sv_safety,
        sv_critical_accel=sv_critical_accel,
        safety_threshold=float(params.safety_threshold),
        change_is_safe=change_is_safe,
        admitted_by=admitted_by,
    )
