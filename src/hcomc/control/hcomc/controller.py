"""HCOMC merge controller (paper Section III): game -> multi-objective optimisation -> Eq. 19.

1. The six key vehicles are taken from the view (:func:`hcomc.control.base.find_key_vehicles`).
2. If VMC is a CAV, the Stackelberg/Harsanyi lane-change game (Section III-B) between VMC (SV)
   and VNR (FV) decides whether lateral cooperation is admissible: when VMC's equilibrium
   action is to change lane, or when its change keeps the Eq. 15 critical acceleration below
   the threshold against every response VNR plays with positive probability. (VMC's own
   payoff cannot see that its change makes room for VR, so "keep" would otherwise always
   win on comfort; the merge objectives then decide between the modes.) An HDV VMC is
   predicted, never commanded, so only VR's own plan is optimised.
3. The optimiser (NSGA-II by default; PSO or SA) searches merge position, VR's lane-change
   duration, the virtual-vehicle horizon and the cooperation mode, evaluating whole
   populations with :class:`~hcomc.control.hcomc.problem.MergeProblem`.
4. Eq. 19 picks one plan from the Pareto set; without any feasible candidate the safe fallback
   applies: VR merges by gap acceptance behind VMC and VMC is not commanded.
"""

from __future__ import annotations

import time

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.control.base import MergeGroup, MergePlan, Mode, TrafficView, elapsed_ms
from hcomc.control.hcomc.problem import OBJECTIVES, KeyState, MergeProblem
from hcomc.control.hcomc.rollout import VMC, VMF, VNF, VR, warm_up
from hcomc.control.lane_change_game import GameVehicle, LaneChangeDecision, lane_change_game
from hcomc.optim.base import Optimizer
from hcomc.optim.registry import make_optimizer
from hcomc.optim.selection import select_eq19
from hcomc.sim.road import Kind

_PHANTOM_AHEAD = 1000.0  # [m] a missing VMF/VNF is a free-road phantom this far ahead


def key_state(view: TrafficView, group: MergeGroup) -> KeyState:
    """Key-vehicle states and parameters in role order, with phantoms for missing leaders."""
    f = view.fleet
    ids = group.as_array()
    present = ids >= 0
    safe = np.where(present, ids, group.vr)
    params = np.column_stack([f.v0, f.T, f.s0, f.a, f.b, f.delta, f.coolness, f.length, f.width])[
        safe
    ]
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
        params=params,
        ids=np.where(ids >= 0, ids, -1),
    )


def _game_vehicle(view: TrafficView, i: int) -> GameVehicle | None:
    if i < 0:
        return None
    f = view.fleet
    return GameVehicle(
        x=float(view.x[i]),
        v=float(view.v[i]),
        length=float(f.length[i]),
        desired_speed=float(f.v0[i]),
        is_cav=bool(f.kind[i] == Kind.CAV),
    )


class HCOMCController:
    """The HCOMC merge controller with a pluggable optimiser."""

    name = "hcomc"

    def __init__(self, config: ScenarioConfig, optimizer: Optimizer | None = None) -> None:
        warm_up()  # load the compiled rollout now, not inside a timed decision
        self.config = config
        self.optimizer = optimizer or make_optimizer(
            config.control.optimizer, pop_size=config.control.pop_size
        )

    def lateral_game(self, view: TrafficView, group: MergeGroup) -> LaneChangeDecision:
        """Section III-B game: may VMC (SV) move to lane 2 in front of VNR (FV)?"""
        cfg = view.config
        kinds = view.fleet.kind
        return lane_change_game(
            _game_vehicle(view, group.vmc),
            _game_vehicle(view, group.vnr),
            _game_vehicle(view, group.vmf),
            _game_vehicle(view, group.vnf),
            sv_idm=cfg.cav,
            fv_idm=cfg.cav if group.vnr >= 0 and kinds[group.vnr] == Kind.CAV else cfg.hdv,
        )

    def problem(self, view: TrafficView, group: MergeGroup, lateral_allowed: bool) -> MergeProblem:
        """The merge problem of this planning instant."""
        cfg = view.config
        return MergeProblem(
            key_state(view, group),
            accel_lane=(cfg.road.accel_lane_start, cfg.road.accel_lane_end),
            lane_width=cfg.road.lane_width,
            lateral_allowed=lateral_allowed,
            vmc_duration=cfg.cav.lane_change_duration,
            transition_tolerance=cfg.lane_change.transition_tolerance,
            emergency_decel=cfg.lane_change.emergency_decel,
            politeness=cfg.lane_change.politeness,
            virtual_max_decel=cfg.control.virtual_max_decel,
            prediction_dt=cfg.control.prediction_dt,
            horizon=(cfg.control.horizon_min, cfg.control.horizon_max),
            post_merge=cfg.control.post_merge,
        )

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
        vmc_cav = bool(view.fleet.kind[group.vmc] == Kind.CAV)
        game = self.lateral_game(view, group) if vmc_cav else None
        lateral_allowed = game is not None and (game.change or game.change_is_safe)
        problem = self.problem(view, group, lateral_allowed=lateral_allowed)
        result = self.optimizer.minimize(problem, budget=self.config.control.budget, rng=rng)
        details = {"pareto_X": result.X, "pareto_F": result.F, "pareto_G": result.G,
                   "feasible": result.feasible, "n_eval": result.n_eval,
                   "optimizer": result.algorithm, "game": game}  # fmt: skip
        if not result.any_feasible:
            return MergePlan(
                group,
                Mode.NONE,
                view.t,
                fallback=True,
                decision_ms=elapsed_ms(start),
                reason="no feasible candidate: VR merges by gap acceptance behind VMC",
                details=details,
            )
        k = select_eq19(
            result.F,
            OBJECTIVES,
            feasible=result.feasible,
            safety_threshold=self.config.control.safety_threshold,
        )
        x = result.X[k]
        chosen = problem.predict(x[None, :])
        lateral = bool(x[3] >= 0.5)
        mode = Mode.NONE if not vmc_cav else Mode.LATERAL if lateral else Mode.LONGITUDINAL
        details.update(chosen=k, prediction=chosen)
        vnr_cav = group.vnr >= 0 and view.fleet.kind[group.vnr] == Kind.CAV
        return MergePlan(
            group,
            mode,
            view.t,
            merge_x=float(x[0]),
            vr_duration=float(x[1]),
            horizon=float(x[2]),
            vv1=chosen.vv1[0] if mode == Mode.LONGITUDINAL else None,
            vv2=chosen.vv2[0] if mode == Mode.LATERAL and vnr_cav else None,
            reason=f"{result.algorithm}: {result.X.shape[0]} Pareto solutions, Eq. 19 pick {k}",
            objectives=dict(zip(OBJECTIVES, map(float, result.F[k]), strict=True)),
            decision_ms=elapsed_ms(start),
            details=details,
        )


__all__ = ["HCOMCController", "key_state"]
