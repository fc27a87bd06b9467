"""The compiled scoring of candidate rows of the merge problem, one row at a time.

:meth:`MergeProblem.evaluate <hcomc.control.hcomc.problem.MergeProblem.evaluate>` (a
population) and :meth:`~hcomc.control.hcomc.problem.MergeProblem.evaluate_row` (simulated
annealing's single rows) score each row in one compiled body (:func:`score_into`): its rollout,
U_fuel, the objectives, the constraints and the penalised cost, on constants prepared once per
planning instant and sequence (:func:`row_constants`). No population of trajectories is
allocated and the values equal those of :meth:`MergeProblem.predict
<hcomc.control.hcomc.problem.MergeProblem.predict>` bit for bit. :func:`load_prediction_kernels`
loads these kernels, and the others a decision needs, once per process.
"""

from __future__ import annotations

import functools

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.config import IDMParams
from hcomc.control.hcomc.problem_terms import CONSTRAINTS, G_LATERAL, G_SEQUENCE, KeyState
from hcomc.control.lane_change_cost import GameVehicle, simulate_sv
from hcomc.control.lane_change_params import GAME_DEFAULT
from hcomc.control.prediction.fuel import _fuel_to_distance_kernel, common_distance_fuel
from hcomc.control.prediction.layout import N_G
from hcomc.control.prediction.population import (
    N_ROLES,
    N_STARTS,
    VMC,
    VR,
    resolve_starts,
    rollout_into,
    rollout_work,
    vmc_tracks,
    warm_up,
    warm_up_instant,
)
from hcomc.control.prediction.scoring import objectives_into, penalised_cost
from hcomc.models.fuel import FUEL_DEFAULT

__all__ = [
    "FUEL_COEFFICIENTS",
    "FUEL_ROLES",
    "load_prediction_kernels",
    "row_constants",
    "score_into",
    "score_row",
    "score_rows",
]

FUEL_COEFFICIENTS = np.array(FUEL_DEFAULT.coefficients(), dtype=np.float64)
"""The fuel model's coefficients (:meth:`~hcomc.models.fuel.FuelParams.coefficients`) as the
kernels take them."""
FUEL_ROLES = (np.array([VR], dtype=np.int64), np.array([VR, VMC], dtype=np.int64))
"""U_fuel's roles: VR alone, or VR and the cooperating vehicle (indexed by its presence)."""


def row_constants(
    state: KeyState,
    starts: FloatArray,
    cf: FloatArray,
    consts: FloatArray,
    n_steps: int,
    cf_fuel: float,
    dt: float,
) -> tuple[object, ...]:
    """The arguments of :func:`score_row` that depend on the planning instant and the key
    group ``state`` alone: its arrays, the resolved ``starts``, the rollout constants, the
    no-merge counterfactual ``cf`` and the cooperating vehicle's fuel in it ``cf_fuel`` [mL],
    and VMC's pre-pass tracks, rolled out here once instead of once per row."""
    tracks = vmc_tracks(
        state.x, state.v, state.a, state.present, state.coop, state.params, consts, n_steps
    )
    return (
        state.x, state.v, state.a, state.present, state.cav, state.coop, state.params,
        starts, consts, n_steps, cf, tracks, FUEL_ROLES[int(bool(state.present[VMC]))], cf_fuel,
        FUEL_COEFFICIENTS, dt,
    )  # fmt: skip


@kernel
def score_row(x0, v0, a0, present, cav, coop, params, starts, consts, n_steps, cf, tracks,
               roles, cf_fuel, coefficients, dt, x, lateral, lateral_violation,
               sequence_violation, threshold, fuel_ref, F, G):  # fmt: skip
    """:meth:`MergeProblem.evaluate_row <hcomc.control.hcomc.problem.MergeProblem.evaluate_row>`
    compiled: the row's rollout
    (:func:`~hcomc.control.prediction.population.rollout_into`), U_fuel, the objectives into
    ``F`` and the constraints into ``G`` as :meth:`MergeProblem.evaluate
    <hcomc.control.hcomc.problem.MergeProblem.evaluate>` writes them (kernel parts, then the
    lateral and sequence flags), and the cost."""
    return score_into(x0, v0, a0, present, cav, coop, params, starts, consts, cf, tracks,
                       roles, cf_fuel, coefficients, dt, x, lateral, lateral_violation,
                       sequence_violation, threshold, fuel_ref, F, G,
                       rollout_work(n_steps))  # fmt: skip


@kernel
def score_into(x0, v0, a0, present, cav, coop, params, starts, consts, cf, tracks, roles,
                cf_fuel, coefficients, dt, x, lateral, lateral_violation, sequence_violation,
                threshold, fuel_ref, F, G, work):  # fmt: skip
    """The body of :func:`score_row`, rolling out into the arrays ``work`` of
    :func:`~hcomc.control.prediction.population.rollout_work` (which a population reuses from row to
    row)."""
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
    G[G_LATERAL] = lateral_violation
    G[G_SEQUENCE] = sequence_violation
    return penalised_cost(F, G, threshold, fuel_ref)


@kernel
def score_rows(x0, v0, a0, present, cav, coop, params, starts, consts, n_steps, cf, tracks,
                roles, cf_fuel, coefficients, dt, X, rows, lateral, allowed, no_behind,
                threshold, fuel_ref, F, G):  # fmt: skip
    """Rows ``rows`` of ``X`` (all of one sequence, whose constants come first as for
    :func:`score_row`) scored into the same rows of ``F`` and ``G``, each by
    :func:`score_row`'s body (``allowed``: whether the sequence admits lateral cooperation;
    ``no_behind``: per row of ``X``, a "behind" row moved ahead for want of a vehicle); the
    rollout's arrays are allocated once for all rows."""
    work = rollout_work(n_steps)
    for q in range(rows.size):
        r = rows[q]
        lat = lateral[r]
        score_into(x0, v0, a0, present, cav, coop, params, starts, consts, cf, tracks, roles,
                    cf_fuel, coefficients, dt, X[r], lat, 1.0 if lat and not allowed else 0.0,
                    1.0 if no_behind[r] else 0.0, threshold, fuel_ref, F[r], G[r],
                    work)  # fmt: skip


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
    score_row(x, v, a, flags, flags, flags, params, starts, consts, n_steps, cf, tracks,
               FUEL_ROLES[1], 0.0, FUEL_COEFFICIENTS, 0.5, row, False, 0.0, 0.0, 1.0, 1.0,
               F, G)  # fmt: skip
    rows, lateral = np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.bool_)  # evaluate's
    score_rows(x, v, a, flags, flags, flags, params, starts, consts, n_steps, cf, tracks,
                FUEL_ROLES[1], 0.0, FUEL_COEFFICIENTS, 0.5, row[None], rows, lateral, True,
                lateral, 1.0, 1.0, F[None], G[None])  # fmt: skip
    trajectory = np.zeros((1, 2, N_ROLES))
    roles = np.zeros(1, dtype=np.int64)
    coefficients = FUEL_DEFAULT.coefficients()
    _fuel_to_distance_kernel(trajectory, roles, *(trajectory,) * 3, 0.25, *coefficients)
    sv = GameVehicle(x=0.0, v=10.0, length=5.0, desired_speed=30.0, is_cav=True)
    simulate_sv(sv, None, None, IDMParams(), GAME_DEFAULT)
