r"""Game-theoretic merge baseline (Liao et al. 2022; Kita 1999).

The paper follows Liao et al. for this benchmark (Section I: "Liao et al. [17], [18] designed
cooperative rules based on game theory, and verified the effectiveness of the proposed merging
method through software simulation and digital twin experiments"; Section IV: "the game theory
model [17]", Table III "Game") and states what it does (Section IV-A): "under Condition 2,
where VMC implements longitudinal cooperation both in FIFO and game theory, while implementing
lateral cooperation in our HCOMC". Liao et al.'s game is played between the ramp vehicle and
the mainline lag vehicle, which may be an HDV. Only the abstracts are known, so it is
implemented as the Kita-style 2x2 game of docs/models.md, executed longitudinally
with the virtual vehicle VV1 (Eq. 8-10); no lateral cooperation, no NSGA-II (paper Table III).

Players and actions (row player first; index 0 / 1):

* VR (row): merge **ahead** of VMC / merge **behind** VMC;
* the lag vehicle (column): **yield** (track VV1, opening a gap for VR) / **not yield** (plain
  car following).

Joint actions are scored from forward predictions of
:meth:`MergeProblem.predict <hcomc.control.hierarchical.problem.MergeProblem.predict>` on the single
longitudinal candidate ``[merge_x, vr_duration, H, 0, row]`` of
:mod:`hcomc.control.longitudinal_candidate`
(fixed merge position and duration, H = VR's predicted arrival time at ``merge_x``). If the
yield cell's virtual vehicles are infeasible in a row, that row's candidate moves to the
nearest feasible one by FIFO's rule
(:func:`hcomc.control.longitudinal_candidate.nearest_feasible`: H lengthened, then the merge
position moved downstream), so that "yield" is a trajectory the lag vehicle can follow; both
cells of the row use the row's candidate:

====================  ======================================  ==============================
cell                  key group predicted                     follower of VR's slot
====================  ======================================  ==============================
(ahead, yield)        usual group, VMC tracks VV1             VMC
(ahead, not yield)    usual group, VMC car-follows only       VMC
(behind, yield)       relabelled group, old VMR tracks VV1    VMR
(behind, not yield)   relabelled group, old VMR car-follows   VMR
====================  ======================================  ==============================

The relabelled group is :func:`hcomc.control.key_group.behind_group` (old VMC → ``vmf``, old
VMR → ``vmc``). "Yield" / "not yield" is obtained by overriding the ``coop`` flag of the ``vmc``
role in a copy of the prediction's key state
(:func:`hcomc.control.longitudinal_candidate.with_cooperation`): the rollout makes that role
follow VV1 iff the flag is set. The simulation state is never touched.

Payoffs: :math:`U = -J`, :math:`J = w_s J_s + w_e J_e + w_c J_c` per player,
over the whole prediction window:

* :math:`J_s = U_{safe}/a_{merg}` (``safety="linear"``, the default), with :math:`U_{safe}`
  the worst Eq. 15 critical acceleration over the follower-leader pairs the merge creates, at
  merge completion (the rollout's ``F[:, 0]``; the Eq. 15 delays follow the vehicles' *true*
  kinds, 0.5 s CAV and 1.0 s HDV, so the cooperation override does not change a vehicle's
  reaction time) and :math:`a_{merg}` = ``control.safety_emergency_decel`` (7.5 m/s²), Eq. 15's
  emergency deceleration: :math:`J_s` is the share of an emergency stop the merge demands of
  the worst follower, 1 when it needs the full emergency deceleration. It is continuous,
  strictly increasing and not capped. :math:`J_s = 10` when the prediction is
  infeasible: a predicted collision, an unavoidable crash (:math:`U_{safe} = \infty`), VR not
  merged in the window, an infeasible virtual vehicle (speed < 0 or deceleration beyond
  ``control.virtual_max_decel``), or a key vehicle predicted to brake harder than
  :math:`a_{merg}` (the same rule as :mod:`hcomc.control.lane_change_game.decision`'s
  :math:`a_{cr} > a_{merg}`: a cut-in that forces emergency braking is a near-crash that
  U_safe at merge completion alone does not show). :math:`J_s` is shared by both players (a
  property of the group) and is the same function as the lane-change game's,
  :func:`hcomc.control.lane_change_game.game_safety.safety_term`.

  Why linear: Kita's merge game has payoffs linear in the safety measure (there the time to
  collision), and Section IV-A says the lag vehicle cooperates. A term capped at the Eq. 19
  threshold, :math:`\min(1, U_{safe}/a_{th})` (:math:`a_{th}` = ``control.safety_threshold``,
  4 m/s²), saturates at highway speed — a CAV at its equilibrium gap at 30 m/s already has
  :math:`U_{safe} \approx 4.6` m/s² — so every cell of most games scores 1 and comfort alone
  decides against yielding, whatever gap the yield opens. That term is kept as the variant
  ``safety="capped"`` (controller ``"game-capped"``), which differs in :math:`J_s` only.
* :math:`J_e = \operatorname{mean}_k |v_k - v_0| / v_0` of the player.
* :math:`J_c = \operatorname{mean}_k a_k^2 / a_{max}^2` of the player, :math:`a_{max}` its
  maximum acceleration parameter (1.4 m/s² CAV, 1.0 m/s² HDV).
* Weights :math:`(w_s, w_e, w_c)`: VR (0.5, 0.3, 0.2) as a CAV, the "normal" type
  (0.4, 0.4, 0.2) as an HDV; the lag vehicle always the "normal" type (0.4, 0.4, 0.2).

Solution:

* VMC a CAV: the cooperative (joint-optimal) cell,
  :func:`hcomc.control.lane_change_game.solvers.solve_cooperative` with SV = VR and FV = the
  lag vehicle.
* VMC an HDV: a pure Nash equilibrium by enumeration
  (:func:`~hcomc.control.merge_game.equilibrium.pure_nash`); among several, the
  one with the largest payoff sum, ties to the first in row-major order. Without a pure
  equilibrium, Kita's closed-form mixed equilibrium
  (:func:`~hcomc.control.merge_game.equilibrium.kita_mixed`)
  :math:`q^* = (a_{22} - a_{12})/(a_{11} - a_{12} - a_{21} + a_{22})`,
  :math:`p^* = (b_{22} - b_{21})/(b_{11} - b_{12} - b_{21} + b_{22})`, and both actions are
  sampled from it with the ``rng`` passed to :meth:`GameController.plan` (VR first).

Execution:

* **ahead**: the usual group; :attr:`Mode.LONGITUDINAL` with VV1 if VMC is a CAV and its
  equilibrium action is yield, otherwise :attr:`Mode.NONE` (VR still starts at ``merge_x``
  if the engine's MOBIL safety check allows; an HDV is never commanded);
* **behind**: the relabelled group; :attr:`Mode.LONGITUDINAL` if the new follower (old VMR)
  exists, is a CAV and the equilibrium column action is yield, otherwise :attr:`Mode.NONE`.

Assumptions (beyond those of :mod:`hcomc.control.fifo`, whose merge position, horizon and
prediction are reused):

* **The column player is the lag vehicle of the row's slot**: VMC in the "ahead" row, the old
  VMR in the "behind" row (Liao et al.'s "mainline lag vehicle"). Each row's column best
  response therefore compares the costs of the vehicle that actually decides to yield. Were the
  column player always VMC, its payoff in the "behind" row would be that of the rollout's VMF
  role (constant speed) and could not depend on its action. A missing lag vehicle has cost 0.
* Whether the game is cooperative or non-cooperative is decided by VMC's kind, as docs/models.md
  says; a non-CAV lag vehicle is never commanded, whatever the cell.
* An HDV's "yield" is predicted as tracking VV1 (an idealised yield), its "not yield" as its
  IDM car following without delays or noise (the rollout's HDV model).
* A chosen cell whose virtual vehicles are infeasible even after the nearest-feasible search
  falls back to gap acceptance (``fallback=True``, mode NONE, ``merge_x`` NaN); its
  :math:`J_s = 10` makes this rare.

References
----------
.. [1] X. Liao et al., "Game Theory-Based Ramp Merging for Mixed Traffic With Unity-SUMO
   Co-Simulation", IEEE Trans. Syst. Man Cybern.: Systems (2022); X. Liao et al., "Cooperative
   ramp merging design and field implementation: a digital twin approach based on
   vehicle-to-cloud communication", IEEE T-ITS (2022) (paper references [17], [18]).
.. [2] H. Kita, "A merging-giveway interaction model of cars in a merging section: a game
   theoretic analysis", Transportation Research Part A 33 (1999) 305-312.
.. [3] P. Hang et al., "Human-like decision making for autonomous driving: a noncooperative
   game theoretic approach", IEEE T-ITS 22(4) (2021) 2076-2087 (style weights).
.. [4] docs/models.md: lane-change game, virtual vehicles, baselines.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from hcomc._typing import FloatArray
from hcomc.config import ScenarioConfig
from hcomc.control.hierarchical.controller import sequence_groups
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_terms import Prediction
from hcomc.control.longitudinal_candidate import (
    last_merge_position,
    longitudinal_rows,
    merge_position,
    nearest_feasible,
    predict_longitudinal,
    reach_horizon,
    virtual_vehicle_feasible,
    with_cooperation,
)
from hcomc.control.merge_game.equilibrium import (
    AHEAD,
    BEHIND,
    NOT_YIELD,
    YIELD,
    GameOutcome,
    solve_merge_game,
)
from hcomc.control.merge_game.payoffs import (
    CAV_WEIGHTS,
    NORMAL_WEIGHTS,
    SAFETY_TERMS,
    player_cost,
    safety_term,
)
from hcomc.control.predicting_baseline import PredictingBaseline, longitudinal_plan
from hcomc.interface import MergeGroup, MergePlan, Mode, PlanDetails, TrafficView, elapsed_ms
from hcomc.road import VMC, VR

__all__ = ["GameController", "GameDetails"]

ROW_NAMES = ("ahead", "behind")
COL_NAMES = ("yield", "not_yield")

PredictionPair = tuple[Prediction, Prediction]


@dataclass(frozen=True, slots=True)
class GameDetails(PlanDetails):
    """What a played merge game reports besides its plan (indices: [row, column], rows
    AHEAD/BEHIND, columns YIELD/NOT_YIELD).

    Attributes
    ----------
    J_vr, J_lag : (2, 2) costs of VR and of the lag vehicle (their payoffs are the negatives).
    terms : cost terms per cell ("ahead/yield", ...) and player ("VR", "lag").
    u_safe : (2, 2) worst Eq. 15 critical acceleration per cell [m/s^2] (inf: VR not merged).
    outcome : the solution played.
    cell : names of the played actions (row, column).
    groups : the usual and the relabelled key group ("ahead", "behind").
    predictions : the prediction of each cell, ``predictions[row][col]``.
    feasible : whether the played cell's prediction satisfies every constraint.
    candidates : each row's candidate (merge position [m], H [s]), ``candidates[row]``.
    safety : the safety term played
        (:data:`~hcomc.control.merge_game.payoffs.SAFETY_TERMS`).
    """

    J_vr: FloatArray
    J_lag: FloatArray
    terms: dict[str, dict[str, dict[str, float]]]
    u_safe: FloatArray
    outcome: GameOutcome
    cell: tuple[str, str]
    groups: tuple[MergeGroup, MergeGroup]
    predictions: tuple[PredictionPair, PredictionPair]
    feasible: bool
    candidates: tuple[tuple[float, float], tuple[float, float]]
    safety: str


class GameController(PredictingBaseline):
    """Kita-style 2x2 ramp-merging game (Liao et al. 2022), longitudinal execution.

    Parameters
    ----------
    config : scenario (reads ``road``, ``cav`` and ``control``).
    safety : the shared safety term, one of
        :data:`~hcomc.control.merge_game.payoffs.SAFETY_TERMS`: ``"linear"`` (the published
        game, controller ``"game"``) or ``"capped"`` (the variant ``"game-capped"``).

    Notes
    -----
    See the module docstring for players, payoffs, solution and every assumption. A played
    game's plan carries :class:`GameDetails`; without a VMC no game is played and the plan
    carries none.
    """

    def __init__(self, config: ScenarioConfig, safety: str = "linear") -> None:
        if safety not in SAFETY_TERMS:
            allowed = ", ".join(map(repr, SAFETY_TERMS))
            raise ValueError(f"GameController: safety = {safety!r}; allowed {allowed}")
        super().__init__(config)
        self.safety = safety
        self.name = "game" if safety == "linear" else f"game-{safety}"

    def candidates(
        self, view: TrafficView, vr: int, yielding: MergeProblem, merge_x: float, duration: float
    ) -> tuple[tuple[float, float], tuple[float, float], Prediction]:
        """Each row's candidate (merge position [m], H [s]) and the (ahead, yield) prediction.

        H is VR's predicted arrival at the fixed merge position
        (:func:`~hcomc.control.longitudinal_candidate.predict_longitudinal`
        in the "ahead" row's yield cell), shared by both rows; a row whose yield cell has an
        infeasible virtual vehicle takes FIFO's nearest feasible candidate instead
        (:func:`hcomc.control.longitudinal_candidate.nearest_feasible`), or keeps its own when
        none is.
        """
        h_max = float(view.config.control.horizon_max)
        first, horizon = predict_longitudinal(
            yielding, merge_x, duration, reach_horizon(view, vr, merge_x), h_max
        )
        x_last = last_merge_position(view, vr)
        nominal = (merge_x, horizon)
        rows = [nominal, nominal]
        for i in (AHEAD, BEHIND):
            pred = (
                first if i == AHEAD else yielding.predict(longitudinal_rows(*nominal, duration, i))
            )
            if not virtual_vehicle_feasible(pred):
                found = nearest_feasible(yielding, merge_x, duration, horizon, h_max, x_last, i)
                rows[i] = found or nominal
        if rows[AHEAD] != nominal:
            first = yielding.predict(longitudinal_rows(*rows[AHEAD], duration, AHEAD))
        return rows[AHEAD], rows[BEHIND], first

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        """Solve the 2x2 game between VR and the lag vehicle and execute its outcome."""
        start = time.perf_counter()
        vr = group.vr
        merge_x, vr_duration = merge_position(view, vr)
        if group.vmc < 0:
            return MergePlan(
                group,
                Mode.NONE,
                view.t,
                merge_x=merge_x,
                vr_duration=vr_duration,
                reason="game: no lane-1 vehicle behind VR, no game to play",
                decision_ms=elapsed_ms(start),
            )
        groups = sequence_groups(view, group)
        problem = self.problem(view, group)
        variants = (with_cooperation(problem, True), with_cooperation(problem, False))
        *rows, first = self.candidates(view, vr, variants[YIELD], merge_x, vr_duration)
        preds: list[list[Prediction]] = [[first, first], [first, first]]
        J_vr, J_lag, u_safe = np.zeros((2, 2)), np.zeros((2, 2)), np.zeros((2, 2))
        terms: dict[str, dict[str, dict[str, float]]] = {}
        w_vr = CAV_WEIGHTS if view.is_cav(vr) else NORMAL_WEIGHTS
        for i in (AHEAD, BEHIND):
            for j in (YIELD, NOT_YIELD):
                if not (i == AHEAD and j == YIELD):
                    preds[i][j] = variants[j].predict(longitudinal_rows(*rows[i], vr_duration, i))
                pred = preds[i][j]
                u_safe[i, j] = float(pred.F[0, 0]) if pred.k_merge[0] >= 0 else np.inf
                j_s = safety_term(pred, problem, u_safe[i, j], self.safety)
                J_vr[i, j], t_vr = player_cost(pred, problem, VR, w_vr, j_s)
                J_lag[i, j], t_lag = player_cost(pred, problem, VMC, NORMAL_WEIGHTS, j_s)
                terms[f"{ROW_NAMES[i]}/{COL_NAMES[j]}"] = {"VR": t_vr, "lag": t_lag}
        cooperative = view.is_cav(group.vmc)
        outcome = solve_merge_game(J_vr, J_lag, cooperative=cooperative, rng=rng)
        exec_group = groups[outcome.row]
        pred = preds[outcome.row][outcome.col]
        cell = (ROW_NAMES[outcome.row], COL_NAMES[outcome.col])
        details = GameDetails(
            J_vr=J_vr,
            J_lag=J_lag,
            terms=terms,
            u_safe=u_safe,
            outcome=outcome,
            cell=cell,
            groups=groups,
            predictions=((preds[0][0], preds[0][1]), (preds[1][0], preds[1][1])),
            feasible=bool((pred.G[0] <= 0.0).all()),
            candidates=(rows[0], rows[1]),
            safety=self.safety,
        )
        what = f"{self.name} ({outcome.kind}): VR {cell[0]} of VMC, lag vehicle {cell[1]}"
        x_played, h_played = rows[outcome.row]
        return longitudinal_plan(
            view,
            exec_group,
            pred,
            merge_x=x_played,
            vr_duration=vr_duration,
            horizon=h_played,
            reason=what,
            start=start,
            details=details,
            sequence=outcome.row,
            commands=outcome.col == YIELD and view.is_cav(exec_group.vmc),
        )
