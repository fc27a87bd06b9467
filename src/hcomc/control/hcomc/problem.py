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
the VMC role (:func:`hcomc.control.base.behind_group`). In lateral mode the cooperating
vehicle moves to lane 2 and VR takes its place in front of the next lane-1 vehicle.

Objectives, all minimised (columns named for :func:`hcomc.optim.selection.select_eq19`):

* ``safety`` — U_safe, Eq. 15 at merge completion over the follower-leader pairs the merge
  creates (VR behind its new leader, VR's new follower behind VR; lateral mode also the
  cooperating vehicle behind its lane-2 leader and the lane-2 follower behind it), the largest
  [m/s^2]; T, D and a_merg from ``config.control``;
* ``fuel`` — U_fuel, Eq. 16 over a **common distance**: VR's fuel to cover the distance it
  would cover without the merge, plus the extra fuel the merge costs the cooperating vehicle
  over its own counterfactual distance [L] (a fixed time window would favour slow plans, and
  comparing a different cooperating vehicle's total fuel would favour one sequence by
  background);
* ``efficiency`` — −U_eff, Eq. 17 as the paper writes it: the incentive of VR's lane change
  at its decision (the predicted state in which VR begins its change), each vehicle's own
  car-following acceleration after the change minus before it (VR: before = its free-road
  acceleration), politeness eta over VMC, VMR, VNR [m/s^2].

Constraints (feasible when <= 0): predicted rectangle collisions among the key vehicles
(count of colliding pair-steps), merge not completed in the window, an unavoidable crash in
Eq. 15 (infinite U_safe), an infeasible virtual vehicle (v < 0 or a < -b_max), a lane change
that would end beyond the acceleration lane [m], lateral mode not admitted by the lane-change
game (or the cooperating vehicle not a CAV), and "behind" without a vehicle to merge behind.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import IDMParams, ScenarioConfig
from hcomc.control.hcomc.rollout import (
    C_A_MERG,
    C_ACCEL_END,
    C_D,
    C_DELAY_CAV,
    C_DELAY_HDV,
    C_DT,
    C_EMERGENCY,
    C_GAMMA,
    C_POLITENESS,
    C_VMC_DUR,
    C_VV_DECEL,
    C_WIDTH,
    N_CONSTS,
    N_ROLES,
    N_STARTS,
    P_A,
    P_LEN,
    P_V0,
    VMC,
    VR,
    counterfactual,
    resolve_starts,
    rollout,
    rollout_into,
    rollout_work,
    vmc_tracks,
    warm_up,
    warm_up_instant,
)
from hcomc.control.hcomc.rollout_fuel import _fuel_to_distance_kernel, common_distance_fuel
from hcomc.control.hcomc.rollout_layout import N_G
from hcomc.control.hcomc.rollout_score import (
    objective_rows,
    objectives_into,
    penalised_cost,
    penalised_costs,
)
from hcomc.control.lane_change_cost import GAME_DEFAULT, GameVehicle, simulate_sv
from hcomc.models.fuel import FUEL_DEFAULT, fuel_rate
from hcomc.safety.critical import SafetyIndex

OBJECTIVES: tuple[str, ...] = ("safety", "fuel", "efficiency")
CONSTRAINTS = (
    "collision",
    "not_merged",
    "unsafe",
    "virtual_vehicle",
    "overrun",
    "lateral",
    "sequence",
)
SEQUENCES = ("ahead", "behind")
AHEAD, BEHIND = 0, 1
MODE_NONE = 1.0
"""With ``control.no_cooperation`` (HCOMC+) the mode variable spans [0, 1.5]: a value of at
least this asks for no cooperation (VMC keeps car following); without it the variable spans
[0, 1] and every row cooperates."""
_G_LATERAL, _G_SEQUENCE = CONSTRAINTS.index("lateral"), CONSTRAINTS.index("sequence")
_FUEL_COEFFICIENTS = np.array(FUEL_DEFAULT.coefficients(), dtype=np.float64)
_FUEL_ROLES = (np.array([VR], dtype=np.int64), np.array([VR, VMC], dtype=np.int64))
"""U_fuel's roles: VR alone, or VR and the cooperating vehicle (indexed by its presence)."""


@dataclass(frozen=True, slots=True)
class KeyState:
    """State and parameters of the six key vehicles at planning time (roles VR … VNR).

    Missing VMF/VNF are replaced by a phantom far ahead at VMC's speed (free road); missing
    VMR/VNR are absent (``present`` False). ``coop`` says which roles cooperate when their
    mode asks it (normally the CAVs); ``starts`` are the start states of VV0 and VV1 (NaN:
    the paper's Eq. 8 start; a replanning controller continues the live virtual vehicles).
    """

    t0: float
    x: FloatArray
    v: FloatArray
    a: FloatArray
    present: BoolArray
    cav: BoolArray
    coop: BoolArray
    params: FloatArray  # (6, 10): v0, T, s0, a, b, delta, coolness, length, width, iidm
    ids: IntArray  # (6,) vehicle indices in the simulation, -1 for absent or phantom
    starts: FloatArray  # (4,) VV0 x, v and VV1 x, v (NaN = default)

    def desired_speed(self, role: int) -> float:
        """Desired speed v0 of a role [m/s] (Eq. 1)."""
        return float(self.params[role, P_V0])

    def max_accel(self, role: int) -> float:
        """Maximum acceleration a of a role [m/s^2] (Eq. 1)."""
        return float(self.params[role, P_A])


@dataclass(frozen=True, slots=True)
class Prediction:
    """Predicted trajectories (C, K + 1, 6) and objective parts of candidate plans."""

    t: FloatArray
    X: FloatArray
    Y: FloatArray
    V: FloatArray
    A: FloatArray
    heading: FloatArray
    k_merge: IntArray
    F: FloatArray
    G: FloatArray
    vv0: FloatArray
    vv1: FloatArray
    vv2: FloatArray
    sequence: IntArray  # (C,) AHEAD or BEHIND


def _without_cooperation(state: KeyState) -> KeyState:
    """``state`` in which the cooperating vehicle (the VMC role) keeps car following: the
    group of a row whose mode is "none"."""
    coop = state.coop.copy()
    coop[VMC] = False
    return replace(state, coop=coop)


def problem_constants(config: ScenarioConfig) -> FloatArray:
    """The rollout's constants vector, every value read from ``config``."""
    safety = SafetyIndex.from_config(config.control)
    consts = np.zeros(N_CONSTS)
    consts[C_DT] = config.control.prediction_dt
    consts[C_ACCEL_END] = config.road.accel_lane_end
    consts[C_WIDTH] = config.road.lane_width
    consts[C_VMC_DUR] = config.cav.lane_change_duration
    consts[C_GAMMA] = np.arctanh(1.0 - 2.0 * config.lane_change.transition_tolerance)
    consts[C_EMERGENCY] = config.lane_change.emergency_decel
    consts[C_VV_DECEL] = config.control.virtual_max_decel
    consts[C_POLITENESS] = config.lane_change.politeness
    consts[C_D] = safety.min_distance
    consts[C_A_MERG] = safety.emergency_decel
    consts[C_DELAY_CAV] = safety.delay_cav
    consts[C_DELAY_HDV] = safety.delay_hdv
    return consts


class MergeProblem:
    """Vectorised HCOMC problem for one planning instant (implements ``optim.base.Problem``).

    Parameters
    ----------
    states : key states of the "ahead" group and of the "behind" group (None when there is
        no vehicle to merge behind).
    config : the scenario; every parameter is read from it.
    lateral_allowed : per sequence, whether the lane-change game admits lateral cooperation.
    """

    n_var = 5
    n_obj = 3
    n_constr = len(CONSTRAINTS)
    objective_names = OBJECTIVES

    def __init__(
        self,
        states: tuple[KeyState, KeyState | None],
        config: ScenarioConfig,
        lateral_allowed: tuple[bool, bool] = (False, False),
    ) -> None:
        self.states = states
        self.state: KeyState = states[0]  # the "ahead" group always exists
        self.config = config
        self.lateral_allowed = lateral_allowed
        self.no_cooperation = bool(config.control.no_cooperation)
        self._variants_of: tuple[KeyState | None, ...] = ()
        self._variants_cache: tuple[KeyState | None, ...] = ()
        self.safety = SafetyIndex.from_config(config.control)
        road, control = config.road, config.control
        start, end = road.accel_lane_start, road.accel_lane_end
        s = self.state
        length = float(s.params[VR, P_LEN])
        self.xl = np.array([max(start, s.x[VR] + 1.0), 3.0, control.horizon_min, 0.0, 0.0])
        mode_max = MODE_NONE + 0.5 if self.no_cooperation else 1.0
        self.xu = np.array(
            [max(end - 3.0 * length, self.xl[0] + 1.0), 6.0, control.horizon_max, mode_max, 1.0]
        )
        self.consts = problem_constants(config)
        # window: VR reaches the lane end at its current speed, changes lane, then settles
        reach = (end - s.x[VR]) / max(s.v[VR], 5.0)
        self.dt = control.prediction_dt
        self.n_steps = int(np.ceil((reach + self.xu[1] + control.post_merge) / self.dt))
        self._fuel_ref = float(fuel_rate(s.v[VR], 0.0) * self.n_steps * self.dt / 1000.0)
        # the no-merge counterfactual of each sequence's key group: candidate-independent, so
        # rolled out once per planning instant, not once per population
        self._no_merge = tuple(
            None
            if st is None
            else np.stack(
                counterfactual(st.x, st.v, st.a, st.present, st.params, self.consts, self.n_steps)
            )
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
        # the per-sequence constants of the compiled scoring, prepared on first use
        self._row_cache: dict[int, tuple[object, ...]] = {}

    @property
    def _variants(self) -> tuple[KeyState | None, ...]:
        """The groups a row is rolled out in, indexed by variant = sequence + 2 * (mode
        "none"): the sequences' groups and, for HCOMC+, the same groups in which the
        cooperating vehicle keeps car following. Derived from ``states`` (a copy of the
        problem with other states, as the baselines make, gets its own)."""
        if self._variants_of is not self.states:
            none = (
                None if st is None or not self.no_cooperation else _without_cooperation(st)
                for st in self.states
            )
            self._variants_cache, self._variants_of = (*self.states, *none), self.states
        return self._variants_cache

    # ------------------------------------------------------------------ evaluate
    def _sequences(self, X: FloatArray) -> tuple[IntArray, BoolArray, BoolArray]:
        """Merge sequence, lateral flag and "behind without a vehicle" flag of every row."""
        seq, lateral, _, no_behind = self._rows(X)
        return seq, lateral, no_behind

    def _rows(self, X: FloatArray) -> tuple[IntArray, BoolArray, IntArray, BoolArray]:
        """Per row: merge sequence, lateral flag, variant (the group it is rolled out in:
        sequence + 2 for mode "none") and the "behind without a vehicle" flag."""
        seq: IntArray = np.where(X[:, 4] >= 0.5, BEHIND, AHEAD).astype(np.int64)
        none: BoolArray = (X[:, 3] >= MODE_NONE) & self.no_cooperation
        lateral: BoolArray = (X[:, 3] >= 0.5) & ~none
        seq[lateral] = AHEAD  # lateral: the cooperating vehicle leaves; VR takes its slot
        no_behind: BoolArray = (seq == BEHIND) & (self.states[BEHIND] is None)
        seq[no_behind] = AHEAD
        variant: IntArray = seq + 2 * none
        return seq, lateral, variant, no_behind

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
            state.x, state.v, state.a, state.present, state.cav, state.coop, state.params,
            starts, X[rows, 0].copy(), X[rows, 1].copy(), X[rows, 2].copy(),
            lateral[rows], self.consts, self.n_steps, cf, resolved=True,
        )  # fmt: skip
        xs, _, vs, as_, _, _, u_safe, u_eff, g, _, _, _ = out
        G[rows, : g.shape[1]] = g
        allowed = self.lateral_allowed[seq]
        G[rows, _G_LATERAL] = np.where(lateral[rows] & ~allowed, 1.0, 0.0)
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
        G[no_behind, _G_SEQUENCE] = 1.0
        t: FloatArray = np.arange(K + 1, dtype=np.float64) * self.dt
        return Prediction(
            t, Xt, Yt, Vt, At, Ht, k_merge, F, G, vv0=vv[0], vv1=vv[1], vv2=vv[2], sequence=seq
        )

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Objectives (n, 3) and constraints (n, 7) of candidate rows ``X`` (n, 5): those of
        :meth:`predict`, without assembling the trajectories.

        An optimiser needs the scores only, so each sequence's rows are scored in one compiled
        call (:func:`_score_rows`) by the single-row body of :meth:`evaluate_row`, on the
        per-sequence constants prepared once per problem: no population of trajectories is
        allocated and VMC's pre-pass tracks are not rolled out again per call. The values are
        those of :meth:`predict` bit for bit (the tests hold both paths to it).
        """
        X = np.ascontiguousarray(np.atleast_2d(X), dtype=np.float64)
        _, lateral, variant, no_behind = self._rows(X)
        F = np.zeros((X.shape[0], self.n_obj))
        G = np.zeros((X.shape[0], self.n_constr))
        for which in range(len(self._variants)):
            rows = np.flatnonzero(variant == which)
            if rows.size == 0 or self._variants[which] is None:
                continue  # "behind" rows without a vehicle to merge behind were moved ahead
            allowed = bool(self.lateral_allowed[which % 2])
            batch = (X, rows, lateral, allowed, no_behind, self.safety.threshold, self._fuel_ref)
            args = (*self._row_constants(which), *batch, F, G)
            _score_rows(*args)
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
        return costs  # the formula's one home: rollout_score.penalised_cost

    # ------------------------------------------------------------ single row (SA)
    def evaluate_row(self, x: FloatArray, F: FloatArray, G: FloatArray) -> float:
        """One candidate ``x`` (5,): its objectives into ``F`` (3,), its constraints into ``G``
        (7,), and its :meth:`scalarise` cost returned, equal bit for bit to
        ``evaluate(x[None])`` and ``scalarise`` of them (``optim.base.RowProblem``; a NaN's
        sign and payload aside, which IEEE 754 leaves open and no optimiser observes).

        Simulated annealing asks for one row at a time, where the machinery of a population
        call (masks, index arrays) costs more than the rollout itself; here one compiled call
        (:func:`_score_row`, the body :meth:`evaluate` runs per row too) rolls out and scores
        the row, on per-sequence constants prepared once per problem. ``F`` and ``G`` must be
        contiguous float64 arrays.
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
        row = (x, lateral, lateral_violation, 1.0 if no_behind else 0.0)
        args = (*self._row_constants(which), *row, self.safety.threshold, self._fuel_ref, F, G)
        cost: float = _score_row(*args)
        return cost

    def _row_constants(self, which: int) -> tuple[object, ...]:
        """The arguments of :func:`_score_row` that depend on the planning instant and the
        sequence alone, prepared on first use."""
        cached = self._row_cache.get(which)
        if cached is not None:
            return cached
        seq = which % 2
        state, cf, starts = self._variants[which], self._no_merge[seq], self._starts[seq]
        # "behind" rows are scored only when that group exists
        assert state is not None
        assert cf is not None
        assert starts is not None
        tracks = vmc_tracks(
            state.x, state.v, state.a, state.present, state.coop, state.params, self.consts,
            self.n_steps,
        )  # fmt: skip
        constants = (
            state.x, state.v, state.a, state.present, state.cav, state.coop, state.params,
            starts, self.consts, self.n_steps, cf, tracks,
            _FUEL_ROLES[int(bool(state.present[VMC]))], self._fuel_no_merge[seq],
            _FUEL_COEFFICIENTS, self.dt,
        )  # fmt: skip
        self._row_cache[which] = constants
        return constants

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
            cf, _FUEL_ROLES[int(with_vmc)], X, V, A, self.dt,
            0.0 if cf_fuel is None else cf_fuel, _FUEL_COEFFICIENTS,
        )  # fmt: skip
        return fuel

    def _counterfactual_fuel(self, cf: FloatArray) -> float:
        """The cooperating vehicle's fuel [mL] over its own distance in the counterfactual."""
        return float(self._fuel_to_distance(cf, (VMC,), *cf[:, None])[0, 0])

    def _fuel_to_distance(
        self, cf: FloatArray, roles: tuple[int, ...], X: FloatArray, V: FloatArray, A: FloatArray
    ) -> FloatArray:
        """Fuel [mL] of ``roles`` (n,) over the distance each covers in the counterfactual
        ``cf`` (3, K + 1, 6), per trajectory of ``X``, ``V``, ``A`` (C, K + 1, 6): (n, C).

        Each vehicle's fuel over the window is completed to that distance at its end speed's
        cruise rate (a negative completion when it went further):
        ``fuel(D) = sum fe dt + fe_cruise(max(v_K, 1)) (D - dx) / max(v_K, 1)``, with the
        rates of :func:`~hcomc.models.fuel.fuel_rate_scalar` (:func:`_fuel_to_distance_kernel`).
        """
        return _fuel_to_distance_kernel(
            cf, np.array(roles, dtype=np.int64), X, V, A, self.dt, *FUEL_DEFAULT.coefficients()
        )


@kernel
def _score_row(x0, v0, a0, present, cav, coop, params, starts, consts, n_steps, cf, tracks,
               roles, cf_fuel, coefficients, dt, x, lateral, lateral_violation,
               sequence_violation, threshold, fuel_ref, F, G):  # fmt: skip
    """:meth:`MergeProblem.evaluate_row` compiled: the row's rollout (:func:`rollout_into`),
    U_fuel, the objectives into ``F`` and the constraints into ``G`` as :meth:`MergeProblem.
    evaluate` writes them (kernel parts, then the lateral and sequence flags), and the cost."""
    return _score_into(x0, v0, a0, present, cav, coop, params, starts, consts, cf, tracks,
                       roles, cf_fuel, coefficients, dt, x, lateral, lateral_violation,
                       sequence_violation, threshold, fuel_ref, F, G,
                       rollout_work(n_steps))  # fmt: skip


@kernel
def _score_into(x0, v0, a0, present, cav, coop, params, starts, consts, cf, tracks, roles,
                cf_fuel, coefficients, dt, x, lateral, lateral_violation, sequence_violation,
                threshold, fuel_ref, F, G, work):  # fmt: skip
    """The body of :func:`_score_row`, rolling out into the arrays ``work`` of
    :func:`rollout_work` (which a population reuses from row to row)."""
    plan = np.empty(3)
    plan[0], plan[1], plan[2] = x[0], x[1], x[2]
    _, u_safe, u_eff = rollout_into(
        x0, v0, a0, present, cav, coop, params, starts, plan, lateral, consts, cf, tracks, work
    )
    X, V, A, g = work[0], work[1], work[3], work[5]
    fuel = common_distance_fuel(cf, roles, X, V, A, dt, cf_fuel, coefficients)
    objectives_into(u_safe, fuel[0], u_eff, F)
    G[:] = 0.0
    G[:N_G] = g
    G[_G_LATERAL] = lateral_violation
    G[_G_SEQUENCE] = sequence_violation
    return penalised_cost(F, G, threshold, fuel_ref)


@kernel
def _score_rows(x0, v0, a0, present, cav, coop, params, starts, consts, n_steps, cf, tracks,
                roles, cf_fuel, coefficients, dt, X, rows, lateral, allowed, no_behind,
                threshold, fuel_ref, F, G):  # fmt: skip
    """Rows ``rows`` of ``X`` (all of one sequence, whose constants come first as for
    :func:`_score_row`) scored into the same rows of ``F`` and ``G``, each by
    :func:`_score_row`'s body (``allowed``: whether the sequence admits lateral cooperation;
    ``no_behind``: per row of ``X``, a "behind" row moved ahead for want of a vehicle); the
    rollout's arrays are allocated once for all rows."""
    work = rollout_work(n_steps)
    for q in range(rows.size):
        r = rows[q]
        lat = lateral[r]
        _score_into(x0, v0, a0, present, cav, coop, params, starts, consts, cf, tracks, roles,
                    cf_fuel, coefficients, dt, X[r], lat, 1.0 if lat and not allowed else 0.0,
                    1.0 if no_behind[r] else 0.0, threshold, fuel_ref, F[r], G[r],
                    work)  # fmt: skip


def default_starts() -> FloatArray:
    """Start states of VV0 and VV1 for a first plan: the Eq. 8 defaults (all NaN)."""
    return np.full(N_STARTS, np.nan)


@functools.cache  # once per process
def load_prediction_kernels() -> None:
    """Load (or compile) the kernels of a decision once per process, so that no timed
    decision pays for it: the rollout (population and single row), U_fuel's and the
    lane-change game's SV simulation."""
    warm_up()
    x, v, a, flags, params, consts, n_steps, cf = warm_up_instant()  # evaluate_row's kernel
    starts = resolve_starts(x, v, params, np.full(N_STARTS, np.nan))
    tracks = vmc_tracks(x, v, a, flags, flags, params, consts, n_steps)
    row, F, G = np.array([800.0, 4.0, 6.0, 0.0, 0.0]), np.empty(3), np.empty(len(CONSTRAINTS))
    _score_row(x, v, a, flags, flags, flags, params, starts, consts, n_steps, cf, tracks,
               _FUEL_ROLES[1], 0.0, _FUEL_COEFFICIENTS, 0.5, row, False, 0.0, 0.0, 1.0, 1.0,
               F, G)  # fmt: skip
    rows, lateral = np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.bool_)  # evaluate's
    _score_rows(x, v, a, flags, flags, flags, params, starts, consts, n_steps, cf, tracks,
                _FUEL_ROLES[1], 0.0, _FUEL_COEFFICIENTS, 0.5, row[None], rows, lateral, True,
                lateral, 1.0, 1.0, F[None], G[None])  # fmt: skip
    trajectory = np.zeros((1, 2, N_ROLES))
    roles = np.zeros(1, dtype=np.int64)
    coefficients = FUEL_DEFAULT.coefficients()
    _fuel_to_distance_kernel(trajectory, roles, *(trajectory,) * 3, 0.25, *coefficients)
    sv = GameVehicle(x=0.0, v=10.0, length=5.0, desired_speed=30.0, is_cav=True)
    simulate_sv(sv, None, None, IDMParams(), GAME_DEFAULT)
