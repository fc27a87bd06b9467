"""The HCOMC multi-objective merge problem (paper Section III-C, Eq. 15-18).

Decision vector (one row per candidate plan):

====  ==========================================================  =====================
col   variable                                                    bounds
====  ==========================================================  =====================
0     VR's lane-change start position on the acceleration lane     [accel start, end - 3L] m
1     VR's lane-change duration                                     [3, 6] s
2     planning horizon H = tf' - t0' of the virtual vehicles        [horizon_min, max] s
3     cooperation mode (< 0.5 longitudinal, >= 0.5 lateral)         [0, 1]
4     merge sequence (< 0.5 VR ahead of VMC, >= 0.5 VR behind VMC)  [0, 1]
====  ==========================================================  =====================

The paper's cooperation modes are longitudinal (Section III-A-1) and lateral (III-A-2): a CAV
VMC always cooperates. The labelled extension HCOMC+ (``control.no_cooperation``) adds the
mode "none", VMC keeps car following and only VR's own merge is planned: the mode variable
then spans [0, 1.5] and a value of at least 1 selects "none".

The merge sequence (Section II-C) is a decision, not a rule: "ahead" puts VR between VMF and
VMC, and VMC cooperates; "behind" puts VR between VMC and VMR, and VMR cooperates. Both are
rolled out with the same kernel on their own key group: for "behind" the group is relabelled
so that the vehicle ahead of VR's slot (VMC) plays the VMF role and the one behind it (VMR)
the VMC role (:func:`hcomc.control.key_group.behind_group`). In lateral mode the cooperating
vehicle moves to lane 2 and VR takes its place in front of the next lane-1 vehicle.

Objectives, all minimised (columns named for :func:`hcomc.equations.selection.select_eq19`):

* ``safety`` — U_safe, Eq. 15 at merge completion over the follower-leader pairs the merge
  creates (VR behind its new leader, VR's new follower behind VR; lateral mode also the
  cooperating vehicle behind its lane-2 leader and the lane-2 follower behind it), the largest
  [m/s^2]; T, D and a_merg from ``config.control``;
* ``fuel`` — U_fuel, Eq. 16 over a **common distance**: VR's fuel to cover the distance it
  would cover without the merge, plus the extra fuel the merge costs the cooperating vehicle
  over its own counterfactual distance [L] (a fixed time window would favour slow plans, and
  comparing a different cooperating vehicle's total fuel would favour one sequence by
  background);
* ``efficiency`` — −U_eff, Eq. 17 with the paper's "acceleration before and after lane
  change": each vehicle's own car-following acceleration after VR's change (the predicted
  state in which VR completes it, VR in lane 1 behind its leader there; lateral mode: the
  cooperating vehicle in lane 2) minus before it (the predicted state in which VR begins it,
  VR on the acceleration lane at its free-road acceleration, the others behind their lanes'
  leaders without VR), politeness eta over VMC, VMR, VNR [m/s^2].

Constraints (feasible when <= 0): predicted rectangle collisions among the key vehicles
(count of colliding pair-steps), merge not completed in the window, an unavoidable crash in
Eq. 15 (infinite U_safe), an infeasible virtual vehicle (v < 0 or a < -b_max), a lane change
that would end beyond the acceleration lane [m], lateral mode not admitted by the lane-change
game (or the cooperating vehicle not a CAV), and "behind" without a vehicle to merge behind.

A replanning HCOMC (HCOMC-R, ``control.replan_period > 0``: a labelled extension; the problem
is made with ``replanning=True``) adds two, which are 0 when planning once:

* ``no_return`` [m] — the merge position lies beyond the point of no return less one replan
  period: ``x_merge <= x_end - (v^2 / (2 b_safe) + s0) - v P``, with VR's predicted speed v
  when it begins its change, MOBIL's b_safe (the deceleration of the engine's release,
  :func:`hcomc.equations.safety.stopping_distance`), VR's jam gap s0 and the replan period P: a
  change the engine refuses at the merge position still leaves a replan before VR is released;
* ``execution`` — the engine's execution criterion fails in the predicted state in which VR
  begins its change: VR's new follower in lane 1 (or VR behind its new leader) would brake
  harder than b_safe [m/s^2], or a bumper gap to either is below MOBIL's minimum gap [m] (the
  engine would refuse to start the change).
"""

from __future__ import annotations

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import ScenarioConfig
from hcomc.control.hierarchical import search
from hcomc.control.hierarchical.problem_setup import (
    FUEL_COEFFICIENTS,
    problem_constants,
    row_constants,
)
from hcomc.control.hierarchical.problem_terms import (
    AHEAD,
    BEHIND,
    CONSTRAINTS,
    G_LATERAL,
    G_SEQUENCE,
    MODE_NONE,
    OBJECTIVES,
    KeyState,
    Prediction,
    canonical_form,
    decode_rows,
)
from hcomc.control.hierarchical.row_scoring import (
    FUEL_ROLES,
    RowConstants,
    constants_handle,
    score_row,
    score_rows,
)
from hcomc.control.prediction.fuel import _fuel_to_distance_kernel, common_distance_fuel
from hcomc.control.prediction.population import (
    N_ROLES,
    P_LEN,
    VMC,
    VR,
    counterfactual,
    resolve_starts,
    rollout,
)
from hcomc.control.prediction.scoring import objective_rows, penalised_costs
from hcomc.equations.fuel import fuel_rate
from hcomc.interface import Ramp
from hcomc.safety.critical import SafetyIndex


class MergeProblem:
    """Vectorised HCOMC problem for one planning instant (implements ``optim.base.Problem``).

    Parameters
    ----------
    states : key states of the "ahead" group and of the "behind" group (None when there is
        no vehicle to merge behind).
    config : the models' parameters; every parameter is read from it.
    lateral_allowed : per sequence, whether the lane-change game admits lateral cooperation.
    replanning : the problem of a replanning HCOMC (HCOMC-R): the constraints ``no_return``
        and ``execution`` apply (module docstring), with ``control.replan_period``.
    ramp : the on-ramp (:class:`hcomc.interface.Ramp`); default: ``config``'s road.
    """

    n_var = 5
    n_obj = 3
    n_constr = len(CONSTRAINTS)
    objective_names = OBJECTIVES
    nsga2_generations = search.nsga2_generations  # optim.nsga2.CompiledGenerations

    def __init__(
        self,
        states: tuple[KeyState, KeyState | None],
        config: ScenarioConfig,
        lateral_allowed: tuple[bool, bool] = (False, False),
        replanning: bool = False,
        ramp: Ramp | None = None,
    ) -> None:
        self.states, self.config = states, config
        self.ramp = Ramp.of(config.road) if ramp is None else ramp
        self.state: KeyState = states[0]  # the "ahead" group always exists
        self.lateral_allowed = lateral_allowed
        self.no_cooperation = bool(config.control.no_cooperation)
        self._variants_of: tuple[KeyState | None, ...] = ()
        self._variants_cache: tuple[KeyState | None, ...] = ()
        self.safety = SafetyIndex.from_config(config.control)
        control, s = config.control, self.state
        start, end = self.ramp.accel_lane_start, self.ramp.accel_lane_end
        length = float(s.params[VR, P_LEN])
        self.xl = np.array([max(start, s.x[VR] + 1.0), 3.0, control.horizon_min, 0.0, 0.0])
        mode_max = MODE_NONE + 0.5 if self.no_cooperation else 1.0
        self.xu = np.array(
            [max(end - 3.0 * length, self.xl[0] + 1.0), 6.0, control.horizon_max, mode_max, 1.0]
        )
        self.replan_period = float(control.replan_period) if replanning else 0.0
        """The replan period whose soundness rules apply (0: a plan made once): ``no_return``,
        ``execution``, the bound of :mod:`~hcomc.control.hierarchical.commitment`."""
        self.consts = problem_constants(config, self.ramp, replanning)
        # window: VR reaches the lane end at its current speed, changes lane, then settles
        reach = (end - s.x[VR]) / max(s.v[VR], 5.0)
        self.dt = control.prediction_dt
        self.n_steps = int(np.ceil((reach + self.xu[1] + control.post_merge) / self.dt))
        self._fuel_ref = float(fuel_rate(s.v[VR], 0.0) * self.n_steps * self.dt / 1000.0)
        # each sequence's no-merge counterfactual: candidate-independent, once per instant
        self._no_merge = tuple(
            None
            if st is None
            else np.stack(counterfactual(st.vehicles(), self.consts, self.n_steps))
            for st in states
        )
        # the virtual vehicles' start states (Eq. 8 defaults resolved) once per sequence
        self._starts = tuple(
            None if st is None else resolve_starts(st.x, st.v, st.params, st.starts)
            for st in states
        )
        # the cooperating vehicle's counterfactual fuel of U_fuel, once per sequence
        self._fuel_no_merge = tuple(
            0.0 if cf is None else self._counterfactual_fuel(cf) for cf in self._no_merge
        )
        # the constants of the compiled scoring, prepared on first use (:meth:`scoring`)
        self._scoring_of: tuple[KeyState | None, ...] = ()
        self._scoring_cache: tuple[tuple[RowConstants, ...], BoolArray, BoolArray]

    @property
    def _variants(self) -> tuple[KeyState | None, ...]:
        """The groups a row is rolled out in, indexed by variant = sequence + 2 * (mode
        "none"): the sequences' groups and, for HCOMC+, the same groups in which the
        cooperating vehicle keeps car following. Derived from ``states`` (a copy of the
        problem with other states, as the baselines make, gets its own)."""
        if self._variants_of is not self.states:
            none = (
                None if st is None or not self.no_cooperation else st.with_vmc_cooperation(False)
                for st in self.states
            )
            self._variants_cache, self._variants_of = (*self.states, *none), self.states
        return self._variants_cache

    # ------------------------------------------------------------------ evaluate
    def canonical_rows(self, X: FloatArray) -> FloatArray:
        """``X`` with the mode and sequence variables set to one value of what they select
        (:func:`~hcomc.control.hierarchical.problem_terms.canonical_form`): rows with equal
        canonical rows have equal values, so an optimiser evaluates one of them
        (``optim.base.CanonicalProblem``)."""
        X = np.ascontiguousarray(np.atleast_2d(X), dtype=np.float64)
        out: FloatArray = canonical_form(X, self.no_cooperation, self.states[BEHIND] is not None)
        return out

    def _rows(self, X: FloatArray) -> tuple[IntArray, BoolArray, IntArray, BoolArray]:
        """Per row: merge sequence, lateral flag, variant (the group it is rolled out in:
        sequence + 2 for mode "none") and the "behind without a vehicle" flag
        (:func:`~hcomc.control.hierarchical.problem_terms.decode_rows`)."""
        X = np.ascontiguousarray(X, dtype=np.float64)
        decoded: tuple[IntArray, BoolArray, IntArray, BoolArray]
        decoded = decode_rows(X, self.no_cooperation, self.states[BEHIND] is not None)
        return decoded

    def sequences(self, X: FloatArray) -> IntArray:
        """The merge sequence (AHEAD or BEHIND) each row is rolled out in."""
        return self._rows(np.atleast_2d(np.asarray(X, dtype=np.float64)))[0]

    def modes(self, X: FloatArray) -> list[str]:
        """The cooperation mode each row asks for: "longitudinal", "lateral" or "none"."""
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        _, lateral, variant, _ = self._rows(X)
        return [
            "lateral" if lat else "none" if var >= 2 else "longitudinal"
            for lat, var in zip(lateral.tolist(), variant.tolist(), strict=True)
        ]

    def _score(
        self, which: int, rows: IntArray, X: FloatArray, lateral: BoolArray, G: FloatArray
    ) -> tuple[FloatArray, tuple[FloatArray, ...]] | None:
        """Roll out ``rows`` of ``X`` in variant ``which``: their objectives (writing their
        constraints into ``G``) and the kernel's outputs; None if there is nothing to roll."""
        seq = which % 2
        state, cf, starts = self._variants[which], self._no_merge[seq], self._starts[seq]
        if rows.size == 0 or state is None or cf is None or starts is None:
            return None
        out = rollout(
            state.vehicles(), starts, X[rows, 0].copy(), X[rows, 1].copy(), X[rows, 2].copy(),
            lateral[rows], self.consts, self.n_steps, cf, resolved=True,
        )  # fmt: skip
        xs, _, vs, as_, _, _, u_safe, u_eff, g, _, _, _ = out
        G[rows, : g.shape[1]] = g
        allowed = self.lateral_allowed[seq]
        G[rows, G_LATERAL] = np.where(lateral[rows] & ~allowed, 1.0, 0.0)
        fuel = self._fuel(xs, vs, as_, cf, state, self._fuel_no_merge[seq])
        return objective_rows(u_safe, fuel, u_eff), out

    def predict(self, X: FloatArray) -> Prediction:
        """Roll out every candidate row of ``X`` and compute its objectives and constraints."""
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        seq, lateral, variant, no_behind = self._rows(X)
        n, K = X.shape[0], self.n_steps
        shape = (n, K + 1, N_ROLES)
        Xt, Yt, Vt, At, Ht = (np.zeros(shape) for _ in range(5))
        k_merge = np.full(n, -1, dtype=np.int64)
        F = np.zeros((n, self.n_obj))
        G = np.zeros((n, self.n_constr))
        vv = [np.zeros((n, 4)) for _ in range(3)]
        for which in range(len(self._variants)):
            rows = np.flatnonzero(variant == which)
            scored = self._score(which, rows, X, lateral, G)
            if scored is None:
                continue
            F[rows], out = scored
            xs, ys, vs, as_, hs, km, _, _, _, v0_, v1_, v2_ = out
            Xt[rows], Yt[rows], Vt[rows], At[rows], Ht[rows] = xs, ys, vs, as_, hs
            k_merge[rows] = km
            for dst, src in zip(vv, (v0_, v1_, v2_), strict=True):
                dst[rows] = src
        G[no_behind, G_SEQUENCE] = 1.0
        t: FloatArray = np.arange(K + 1, dtype=np.float64) * self.dt
        return Prediction(
            t, Xt, Yt, Vt, At, Ht, k_merge, F, G, vv0=vv[0], vv1=vv[1], vv2=vv[2], sequence=seq
        )

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Objectives (n, 3) and constraints (n, 9) of candidate rows ``X`` (n, 5): F(x) and the
        constraints of Ω in Eq. 18, those of :meth:`predict` bit for bit (the tests hold both
        paths to it), without the trajectories: every row in one compiled call
        (:func:`~hcomc.control.hierarchical.row_scoring.score_rows`) of :meth:`evaluate_row`'s
        body, on the per-variant constants prepared once per problem.
        """
        X = np.ascontiguousarray(np.atleast_2d(X), dtype=np.float64)
        _, lateral, variant, no_behind = self._rows(X)
        F = np.zeros((X.shape[0], self.n_obj))
        G = np.zeros((X.shape[0], self.n_constr))
        score_rows(*self.scoring(), X, variant, lateral, no_behind, F, G)
        return F, G

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        """Eq. 19 as one cost for PSO and SA, with the U_safe gate as a penalty.

        ``U = U_fuel / U_fuel,ref + (-U_eff) / (1 m/s^2) + 10 max(0, U_safe - threshold)
        + 1000 sum(max(G, 0))``: Eq. 19's sum of the two normalised costs with fixed scales
        (a single-objective optimiser has no Pareto set to min-max normalise over); the
        reference fuel is VR's cruise fuel over the window, the threshold
        ``control.safety_threshold``.
        """
        F = np.ascontiguousarray(F, dtype=np.float64)
        G = np.ascontiguousarray(G, dtype=np.float64)
        costs: FloatArray = penalised_costs(F, G, self.safety.threshold, self._fuel_ref)
        return costs  # the formula's one home: prediction.scoring.penalised_cost

    # ------------------------------------------------------------ single row (SA)
    def evaluate_row(self, x: FloatArray, F: FloatArray, G: FloatArray) -> float:
        """One candidate ``x`` (5,): its objectives into ``F`` (3,), its constraints into ``G``
        (9,), and its :meth:`scalarise` cost returned, equal bit for bit to
        ``evaluate(x[None])`` and ``scalarise`` of them (``optim.base.RowProblem``; a NaN's
        sign and payload aside, which IEEE 754 leaves open and no optimiser observes).

        Simulated annealing asks for one row at a time, where the machinery of a population
        call (masks, index arrays) costs more than the rollout itself; here one compiled call
        (:func:`~hcomc.control.hierarchical.row_scoring.score_row`, the body :meth:`evaluate`
        runs per row too) rolls out and scores the row, on per-sequence constants prepared once per
        problem. ``F`` and ``G`` must be contiguous float64 arrays.
        """
        x = np.asarray(x, dtype=np.float64)
        none = self.no_cooperation and bool(x[3] >= MODE_NONE)  # the rules of _rows, one row
        lateral = bool(x[3] >= 0.5) and not none
        which = BEHIND if x[4] >= 0.5 and not lateral else AHEAD
        no_behind = which == BEHIND and self.states[BEHIND] is None
        if no_behind:
            which = AHEAD
        lateral_violation = 1.0 if lateral and not self.lateral_allowed[which] else 0.0
        which += 2 * none
        sequence_violation = 1.0 if no_behind else 0.0
        constants = self._row_constants(which)
        return score_row(constants, x, lateral, lateral_violation, sequence_violation, F, G)

    def _row_constants(self, which: int) -> RowConstants:
        """What :func:`~hcomc.control.hierarchical.row_scoring.score_row` takes from the planning
        instant and the variant ``which`` (:meth:`scoring`)."""
        return self.scoring()[0][which]

    def scoring(self) -> tuple[tuple[RowConstants, ...], BoolArray, BoolArray]:
        """What :func:`~hcomc.control.hierarchical.row_scoring.score_rows` takes from the
        problem, prepared on first use: every variant's constants (``row_constants`` in a
        ``constants_handle``; an absent variant's place holds the "ahead" group's, which always
        exists), which variants exist, per sequence whether it admits lateral cooperation."""
        if self._scoring_of is not self.states:  # first use, or a copy with other states
            on = [state is not None for state in self._variants]
            made = {w: self._constants(w) for w in range(len(on)) if on[w]}
            variants = tuple(made[w if on[w] else AHEAD] for w in range(len(on)))
            allowed = np.array(self.lateral_allowed, dtype=np.bool_)
            self._scoring_cache = (variants, np.array(on), allowed)
            self._scoring_of = self.states
        return self._scoring_cache

    def _constants(self, which: int) -> RowConstants:
        """The constants handle of the existing variant ``which``."""
        seq = which % 2
        state, cf, starts = self._variants[which], self._no_merge[seq], self._starts[seq]
        assert state is not None
        assert cf is not None
        assert starts is not None
        return constants_handle(row_constants(
            state, starts, cf, self.consts, self.n_steps, self._fuel_no_merge[seq], self.dt,
            self.safety.threshold, self._fuel_ref,
        ))  # fmt: skip

    # ----------------------------------------------------------------- helpers
    def _fuel(
        self,
        X: FloatArray,
        V: FloatArray,
        A: FloatArray,
        cf: FloatArray,
        state: KeyState,
        cf_fuel: float | None = None,
    ) -> FloatArray:
        """U_fuel over a common distance [L] (module docstring): VR's fuel, plus the
        cooperating vehicle's minus its fuel in the counterfactual ``cf`` (``cf_fuel``,
        computed when None; the problem computes it once per sequence at set-up)."""
        with_vmc = bool(state.present[VMC])
        if with_vmc and cf_fuel is None:
            cf_fuel = self._counterfactual_fuel(cf)
        fuel: FloatArray = common_distance_fuel(
            cf, FUEL_ROLES[int(with_vmc)], X, V, A, self.dt,
            0.0 if cf_fuel is None else cf_fuel, FUEL_COEFFICIENTS,
        )  # fmt: skip
        return fuel

    def _counterfactual_fuel(self, cf: FloatArray) -> float:
        """The cooperating vehicle's fuel [mL] over its own distance in the counterfactual."""
        return float(self._fuel_to_distance(cf, (VMC,), *cf[:, None])[0, 0])

    def _fuel_to_distance(
        self, cf: FloatArray, roles: tuple[int, ...], X: FloatArray, V: FloatArray, A: FloatArray
    ) -> FloatArray:
        """Fuel [mL] of ``roles`` (n,) over the distance each covers in the counterfactual
        ``cf`` (3, K + 1, 6), per trajectory of ``X``, ``V``, ``A`` (C, K + 1, 6): (n, C),
        completed to that distance at the end speed's cruise rate
        (:func:`~hcomc.control.prediction.fuel._fuel_to_distance_kernel`)."""
        return _fuel_to_distance_kernel(
            cf, np.array(roles, dtype=np.int64), X, V, A, self.dt, FUEL_COEFFICIENTS
        )
