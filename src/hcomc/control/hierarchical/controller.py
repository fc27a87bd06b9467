"""HCOMC merge controller (paper Section III): game -> multi-objective optimisation -> Eq. 19.

1. The six key vehicles are taken from the view
   (:func:`hcomc.control.key_group.find_key_vehicles`); the "behind" sequence uses the
   relabelled group of :func:`hcomc.control.key_group.behind_group`.
2. For each sequence whose cooperating vehicle is a CAV, the Stackelberg/Harsanyi lane-change
   game (Section III-B) between that vehicle (SV) and its lane-2 follower (FV) decides whether
   lateral cooperation is admissible: when SV's equilibrium action is to change lane, or when
   its change keeps the Eq. 15 critical acceleration below the threshold against every
   response FV plays with positive probability. (SV's own payoff cannot see that its change
   makes room for VR, so "keep" would otherwise always win on comfort; the merge objectives
   then decide between the modes.) An HDV is predicted, never commanded.
3. The optimiser (NSGA-II by default; PSO or SA) searches merge position, VR's lane-change
   duration, the virtual-vehicle horizon, the cooperation mode and the merge sequence,
   evaluating whole populations with :class:`~hcomc.control.hierarchical.problem.MergeProblem`. When
   the engine replans (receding horizon), the previous Pareto set of the same VR seeds the
   search and the live virtual vehicles are continued, so the commanded motion stays smooth.
4. Eq. 19 picks one plan from the Pareto set; without any feasible candidate the safe fallback
   applies: VR merges by gap acceptance and nobody is commanded. A replan keeps the live
   plan's cooperating vehicle, mode and sequence unless it has become infeasible or fails
   Eq. 19's safety gate (:mod:`~hcomc.control.hierarchical.commitment`).

The labelled extension HCOMC+ (``control.no_cooperation``) also lets the optimiser choose to
leave the mainline alone (mode "none"); the paper's HCOMC always commands a CAV VMC.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from hcomc._typing import FloatArray
from hcomc.config import ScenarioConfig
from hcomc.control.hierarchical.commitment import choose, continuations, executed
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_setup import load_prediction_kernels
from hcomc.control.hierarchical.problem_terms import (
    AHEAD,
    OBJECTIVES,
    SEQUENCES,
    KeyState,
    Prediction,
    default_starts,
)
from hcomc.control.key_group import behind_group
from hcomc.control.lane_change_game.decision import LaneChangeDecision, game_params, game_vehicle
from hcomc.control.lane_change_game.decision import lane_change_game as play_lane_change_game
from hcomc.control.prediction.population import (
    S_VV0_V,
    S_VV0_X,
    S_VV1_V,
    S_VV1_X,
    VMC,
    VMF,
    VNF,
    VR,
)
from hcomc.equations.selection import eq19_branch, select_eq19
from hcomc.equations.virtual_vehicle import cubic_state
from hcomc.interface import MergeGroup, MergePlan, Mode, PlanDetails, TrafficView, elapsed_ms
from hcomc.optim.base import Optimizer, ParetoResult
from hcomc.optim.registry import optimizer_from_config
from hcomc.road import Kind

_PHANTOM_AHEAD = 1000.0  # [m] a missing VMF/VNF is a free-road phantom this far ahead


@dataclass(frozen=True, slots=True)
class HCOMCDetails(PlanDetails):
    """What an HCOMC decision reports besides its plan.

    Attributes
    ----------
    pareto : the optimiser's returned set (decision vectors, objectives, constraints,
        feasibility, evaluations spent, optimiser name).
    games : the Section III-B lateral game per sequence ("ahead", "behind"): the "ahead"
        sequence's, None where its cooperating vehicle is not a CAV; always None for
        "behind", whose game is not played: a lateral candidate is always rolled out in the
        "ahead" group (the cooperating vehicle leaves lane 1 and VR takes its slot), so that
        game could not change the decision.
    chosen : row of ``pareto`` that Eq. 19 picked (-1: no feasible row, the fallback applies;
        ``len(pareto.X)`` or more: a row keeping the live plan's cooperation, added by the
        commitment rule, :func:`~hcomc.control.hierarchical.commitment.continuations`).
    prediction : the prediction of the chosen row (None without a pick).
    eq19_branch : the Eq. 19 case that picked it ("" without a pick).
    commitment : what the commitment rule of a replan did: "kept" (the live plan's
        cooperating vehicle, mode and sequence) or "switched: ..." with the reason (no
        feasible candidate keeps the live cooperation, every one keeping it fails Eq. 19's
        safety gate, or the Eq. 19 cost it gains); "" for a first plan.
    """

    pareto: ParetoResult
    games: tuple[LaneChangeDecision | None, LaneChangeDecision | None]
    chosen: int = -1
    prediction: Prediction | None = None
    eq19_branch: str = ""
    commitment: str = ""

    @property
    def game(self) -> LaneChangeDecision | None:
        """The lateral game of the "ahead" sequence (the key group as identified)."""
        return self.games[AHEAD]


def key_state(view: TrafficView, group: MergeGroup, starts: np.ndarray | None = None) -> KeyState:
    """Key-vehicle states and parameters in role order, with phantoms for missing leaders."""
    f = view.fleet
    ids = group.as_array()
    present = ids >= 0
    safe = np.where(present, ids, group.vr)
    columns = [f.v0, f.T, f.s0, f.a, f.b, f.delta, f.coolness, f.length, f.width, f.iidm]
    params = np.column_stack(columns).astype(np.float64)[safe]
    x, v, a = view.x[safe].copy(), view.v[safe].copy(), view.a[safe].copy()
    cav = f.kind[safe] == Kind.CAV
    anchor = group.vmc if group.vmc >= 0 else group.vr
    for role in (VMF, VNF):
        if not present[role]:
            x[role] = view.x[anchor] + _PHANTOM_AHEAD
            v[role], a[role], cav[role] = f.v0[anchor], 0.0, True
            params[role] = params[VMC if group.vmc >= 0 else VR]
            present[role] = True
    x[~present] = -1e9  # absent followers never interact
    return KeyState(
        t0=view.t,
        x=x,
        v=v,
        a=a,
        present=present,
        cav=cav,
        coop=cav.copy(),
        params=params,
        ids=np.where(ids >= 0, ids, -1),
        starts=default_starts() if starts is None else starts,
    )


def virtual_states(
    plan: MergePlan, t: float, x: FloatArray, v: FloatArray, a: FloatArray
) -> dict[str, tuple[float, float, float]]:
    """State (x, v, a) at time t of each virtual vehicle ``plan`` has ("vv0", "vv1", "vv2").

    Within the horizon a virtual vehicle is its cubic; after it, VV0 is the projection of VR's
    future leader (``group.vmf``, if any) and VV1 that of VR; VV2 ends at the horizon. The
    engine executes exactly these, and a replanning controller continues them.
    """
    g, tau = plan.group, t - plan.t0
    out: dict[str, tuple[float, float, float]] = {}
    after = {"vv0": g.vmf, "vv1": g.vr, "vv2": -1}
    for name, coeffs in (("vv0", plan.vv0), ("vv1", plan.vv1), ("vv2", plan.vv2)):
        if coeffs is None:
            continue
        if tau <= plan.horizon:
            xv, vv, av = cubic_state(coeffs, tau)
            out[name] = (float(xv), float(vv), float(av))
        elif after[name] >= 0:
            j = after[name]
            out[name] = (float(x[j]), float(v[j]), float(a[j]))
    return out


def continuation_starts(view: TrafficView, group: MergeGroup) -> np.ndarray:
    """Start states of VV0 and VV1 that continue the live plan of ``group.vr`` (NaN: none).

    VV0 (VR's virtual leader) is continued whenever a plan is live; VV1 only when the same
    vehicle keeps cooperating, i.e. the live plan's cooperating vehicle is ``group.vmc``.
    """
    starts = default_starts()
    live = view.live_plan(group.vr)
    if live is None:
        return starts
    states = virtual_states(live, view.t, view.x, view.v, view.a)
    if "vv0" in states:
        starts[S_VV0_X], starts[S_VV0_V] = states["vv0"][:2]
    if "vv1" in states and live.group.vmc == group.vmc:
        starts[S_VV1_X], starts[S_VV1_V] = states["vv1"][:2]
    return starts


def sequence_groups(view: TrafficView, group: MergeGroup) -> tuple[MergeGroup, MergeGroup]:
    """The executed key groups of the two merge sequences, ("ahead", "behind")."""
    return group, behind_group(view, group)


def merge_problem(
    view: TrafficView,
    group: MergeGroup,
    lateral_allowed: tuple[bool, bool] = (False, False),
    replanning: bool = False,
) -> MergeProblem:
    """The merge problem of both sequences at this planning instant (live plans continued);
    ``replanning``: HCOMC-R's, with the constraints of a replanning controller
    (:class:`~hcomc.control.hierarchical.problem.MergeProblem`)."""
    groups = sequence_groups(view, group)
    states = tuple(key_state(view, g, continuation_starts(view, g)) for g in groups)
    return MergeProblem((states[0], states[1]), view.config, lateral_allowed, replanning,
                        ramp=view.ramp)  # fmt: skip


class HCOMCController:
    """The HCOMC merge controller with a pluggable optimiser."""

    name = "hcomc"

    def __init__(self, config: ScenarioConfig, optimizer: Optimizer | None = None) -> None:
        load_prediction_kernels()  # load the compiled kernels now, not inside a timed decision
        self.config = config
        self.optimizer = optimizer or optimizer_from_config(config.control)
        self._pareto: dict[int, np.ndarray] = {}  # last Pareto set per VR (warm start)

    def lateral_game(self, view: TrafficView, group: MergeGroup) -> LaneChangeDecision | None:
        """Section III-B game: may the cooperating vehicle (SV) move to lane 2 before VNR?"""
        if not view.is_cav(group.vmc):
            return None
        cfg = view.config
        fv_cav = view.is_cav(group.vnr)
        sv = game_vehicle(view.x, view.v, view.fleet, group.vmc)
        assert sv is not None  # a CAV is present
        return play_lane_change_game(
            sv,
            game_vehicle(view.x, view.v, view.fleet, group.vnr),
            game_vehicle(view.x, view.v, view.fleet, group.vmf),
            game_vehicle(view.x, view.v, view.fleet, group.vnf),
            params=game_params(cfg, view.ramp.lane_width),
            sv_idm=cfg.cav,
            fv_idm=cfg.cav if fv_cav else cfg.hdv,
        )

    def problem(
        self, view: TrafficView, group: MergeGroup
    ) -> tuple[MergeProblem, tuple[LaneChangeDecision | None, LaneChangeDecision | None]]:
        """The merge problem of this planning instant and the lateral games per sequence
        (only the "ahead" sequence's is played, see :class:`HCOMCDetails`)."""
        game = self.lateral_game(view, group)
        allowed = game is not None and game.admits(self.config.control.lateral_safety_rule)
        replanning = self.config.control.replan_period > 0.0  # HCOMC-R
        problem = merge_problem(view, group, (allowed, False), replanning)
        return problem, (game, None)

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        """Plan VR's merge and the key vehicles' cooperation."""
        start = time.perf_counter()
        if group.vmc < 0:
            return MergePlan(
                group,
                Mode.NONE,
                view.t,
                reason="no lane-1 vehicle behind VR",
                decision_ms=elapsed_ms(start),
            )
        problem, games = self.problem(view, group)
        budget = self.config.control.budget
        result = self.optimizer.minimize(
            problem, budget=budget, rng=rng, initial=self._pareto.get(group.vr)
        )
        groups = sequence_groups(view, group)
        picked = self._pick(view, groups, problem, result) if result.any_feasible else None
        if picked is None:  # no feasible candidate (HCOMC-R: none that does not drift)
            self._pareto.pop(group.vr, None)
            return MergePlan(
                group,
                Mode.NONE,
                view.t,
                fallback=True,
                decision_ms=elapsed_ms(start),
                reason="no feasible candidate: VR merges by gap acceptance",
                details=HCOMCDetails(pareto=result, games=games),
            )
        self._pareto[group.vr] = result.X[result.feasible]
        x, f, k, commitment = picked
        chosen = problem.predict(x[None, :])
        seq, exec_group, mode = executed(view, groups, problem, x)
        details = HCOMCDetails(
            pareto=result,
            games=games,
            chosen=k,
            prediction=chosen,
            eq19_branch=eq19_branch(
                result.F, OBJECTIVES, result.feasible, problem.safety.threshold
            ),
            commitment=commitment,
        )
        return MergePlan(
            exec_group,
            mode,
            view.t,
            merge_x=float(x[0]),
            vr_duration=float(x[1]),
            horizon=float(x[2]),
            vv0=chosen.vv0[0].copy() if view.is_cav(group.vr) else None,
            vv1=chosen.vv1[0].copy() if mode == Mode.LONGITUDINAL else None,
            vv2=chosen.vv2[0].copy()
            if mode == Mode.LATERAL and view.is_cav(exec_group.vnr)
            else None,
            reason=f"{result.algorithm}: {result.X.shape[0]} Pareto solutions, Eq. 19 pick {k}"
            + (f", {commitment}" if commitment else ""),
            objectives=dict(zip(OBJECTIVES, map(float, f), strict=True)),
            decision_ms=elapsed_ms(start),
            details=details,
            sequence=SEQUENCES[seq],
        )

    def _pick(
        self,
        view: TrafficView,
        groups: tuple[MergeGroup, MergeGroup],
        problem: MergeProblem,
        result: ParetoResult,
    ) -> tuple[np.ndarray, np.ndarray, int, str] | None:
        """The plan to execute: Eq. 19's pick from the Pareto set for a first plan; for a
        replan, the commitment rule (:mod:`~hcomc.control.hierarchical.commitment`) over the Pareto
        set and the rows keeping the live plan's cooperation. Returns its decision vector,
        objectives, index (in the Pareto set; ``len(result.X)`` or more for an added row) and
        what the rule did ("" for a first plan, "kept", or "switched: ..." with the reason);
        None when no candidate is left (HCOMC-R: every feasible one keeps the live
        cooperation with its merge position further downstream,
        :func:`~hcomc.control.hierarchical.commitment.merge_bound`)."""
        threshold = problem.safety.threshold
        live = view.live_plan(groups[0].vr)
        if live is None or live.fallback:
            k = select_eq19(
                result.F, OBJECTIVES, feasible=result.feasible, safety_threshold=threshold
            )
            return result.X[k], result.F[k], k, ""
        X, F, feasible = result.X, result.F, result.feasible
        rows = continuations(live, groups, problem, view.t)
        if rows is not None:
            f, g = problem.evaluate(rows)
            X, F = np.vstack([X, rows]), np.vstack([F, f])
            feasible = np.append(feasible, np.all(g <= 0.0, axis=1))
        choice = choose(
            view, groups, problem, (X, F, feasible), live, self.config.control.commitment_margin
        )
        if choice.row < 0:
            return None
        return X[choice.row], F[choice.row], choice.row, choice.why


__all__ = [
    "HCOMCController",
    "HCOMCDetails",
    "continuation_starts",
    "key_state",
    "merge_problem",
    "sequence_groups",
]
