"""The compiled scoring of candidate rows of the merge problem, one row at a time.

:meth:`MergeProblem.evaluate <hcomc.control.hierarchical.problem.MergeProblem.evaluate>` (a
population) and :meth:`~hcomc.control.hierarchical.problem.MergeProblem.evaluate_row` (simulated
annealing's single rows) score each row in one compiled body (:func:`score_into`): its rollout,
U_fuel, the objectives, the constraints and the penalised cost, on constants prepared once per
planning instant and sequence (:func:`row_constants`). No population of trajectories is
allocated and the values equal those of :meth:`MergeProblem.predict
<hcomc.control.hierarchical.problem.MergeProblem.predict>` bit for bit.
:func:`load_prediction_kernels` loads these kernels, and the others a decision needs, once per
process.

The constants are a :class:`RowConstants` record, which the kernels receive through its
compiled handle (:func:`constants_handle`), as the engine's step receives its ``CoreArrays``
through ``Core`` (:mod:`hcomc.sim.step.state`): numba types a record argument anew at every
call from Python, reading the names of its fields and of the fields of the records in it,
which would cost simulated annealing a few microseconds per row; a handle costs one
pointer.
"""

from __future__ import annotations

import functools
from typing import Any, NamedTuple

import numpy as np
from numba.core import types
from numba.experimental import structref

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.config import IDMParams
from hcomc.control.hierarchical.problem_terms import CONSTRAINTS, G_LATERAL, G_SEQUENCE, KeyState
from hcomc.control.lane_change_game.params import GAME_DEFAULT
from hcomc.control.prediction.candidate import RolloutWork
from hcomc.control.prediction.fuel import (
    FuelCoefficients,
    _fuel_to_distance_kernel,
    common_distance_fuel,
)
from hcomc.control.prediction.game_players import GameVehicle, simulate_sv
from hcomc.control.prediction.layout import N_G
from hcomc.control.prediction.population import (
    N_ROLES,
    N_STARTS,
    VMC,
    VR,
    KeyVehicles,
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
    "RowConstants",
    "RowConstantsRef",
    "constants_handle",
    "load_prediction_kernels",
    "row_constants",
    "score_into",
    "score_row",
    "score_rows",
]

FUEL_COEFFICIENTS = FuelCoefficients.of(FUEL_DEFAULT)
"""The default fuel model's coefficients as the kernels take them."""
FUEL_ROLES = (np.array([VR], dtype=np.int64), np.array([VR, VMC], dtype=np.int64))
"""U_fuel's roles: VR alone, or VR and the cooperating vehicle (indexed by its presence)."""


class RowConstants(NamedTuple):
    """What the scoring of a row (:func:`score_row`) takes from its problem: the values that
    depend on the planning instant and the key group alone, prepared once per problem and
    sequence (:func:`row_constants`)."""

    key: KeyVehicles  # the key vehicles at the planning instant
    starts: np.ndarray  # (4,) start states of VV0 and VV1 [m, m/s], resolved (no NaN)
    consts: np.ndarray  # (N_CONSTS,) the rollout's constants (C_*)
    n_steps: int  # prediction steps K
    cf: np.ndarray  # (3, K + 1, 6) x, v, a of the no-merge counterfactual [m, m/s, m/s^2]
    tracks: np.ndarray  # (2, K + 1, 2) VMC's pre-pass position and speed per mode [m, m/s]
    fuel_roles: np.ndarray  # U_fuel's roles (one of FUEL_ROLES)
    cf_fuel: float  # the cooperating vehicle's fuel in the counterfactual [mL]
    fuel: FuelCoefficients  # the fuel model
    dt: float  # prediction step [s]
    threshold: float  # U_safe above which the cost's gate penalises [m/s^2]
    fuel_ref: float  # reference fuel the cost divides U_fuel by [L]


@structref.register
class RowConstantsType(types.StructRef):
    """numba type of :class:`RowConstantsRef`."""

    def preprocess_fields(self, fields: Any) -> tuple[tuple[str, Any], ...]:
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class RowConstantsRef(structref.StructRefProxy):
    """The scoring kernels' handle on a :class:`RowConstants` (the same arrays, in fields of
    the same names), passed to them as one pointer; made by :func:`constants_handle`."""


structref.define_constructor(RowConstantsRef, RowConstantsType, list(RowConstants._fields))
structref.define_boxing(RowConstantsType, RowConstantsRef)


def constants_handle(constants: RowConstants) -> RowConstants:
    """The handle (:class:`RowConstantsRef`) in which the scoring kernels take ``constants``.
    It is typed as the record whose fields it has, which compiled code reads (Python code
    reads the record)."""
    handle: RowConstants = _new_ref(*constants)
    return handle


@kernel
def _new_ref(*values: Any) -> Any:
    """A :class:`RowConstantsRef` over ``values`` (the fields of :class:`RowConstants`, in
    order), made in compiled code: numba's own constructor path would compile anew in every
    process, this kernel is loaded from numba's cache."""
    return RowConstantsRef(*values)


def row_constants(
    state: KeyState,
    starts: FloatArray,
    cf: FloatArray,
    consts: FloatArray,
    n_steps: int,
    cf_fuel: float,
    dt: float,
    threshold: float,
    fuel_ref: float,
) -> RowConstants:
    """The :class:`RowConstants` of the key group ``state``: its vehicles, the resolved
    ``starts``, the rollout constants, the no-merge counterfactual ``cf`` and the cooperating
    vehicle's fuel in it ``cf_fuel`` [mL], the cost's ``threshold`` and ``fuel_ref``, and
    VMC's pre-pass tracks, rolled out here once instead of once per row."""
    key = state.vehicles()
    tracks = vmc_tracks(key, consts, n_steps)
    roles = FUEL_ROLES[int(bool(state.present[VMC]))]
    return RowConstants(
        key, starts, consts, int(n_steps), cf, tracks, roles, float(cf_fuel), FUEL_COEFFICIENTS,
        float(dt), float(threshold), float(fuel_ref),
    )  # fmt: skip


@kernel
def score_row(
    constants: RowConstants, x: np.ndarray, lateral: bool, lateral_violation: float,
    sequence_violation: float, F: np.ndarray, G: np.ndarray,
) -> float:  # fmt: skip
    """:meth:`~hcomc.control.hierarchical.problem.MergeProblem.evaluate_row` compiled: the
    rollout of row ``x`` (5,) with mode ``lateral``
    (:func:`~hcomc.control.prediction.population.rollout_into`), U_fuel, the objectives into
    ``F`` and the constraints into ``G`` as :meth:`MergeProblem.evaluate
    <hcomc.control.hierarchical.problem.MergeProblem.evaluate>` writes them (kernel parts, then
    the lateral and sequence flags ``lateral_violation`` and ``sequence_violation``), and the
    cost; ``constants`` are the row's :class:`RowConstants`, as their
    :func:`constants_handle`."""
    work = rollout_work(constants.n_steps)
    return score_into(constants, x, lateral, lateral_violation, sequence_violation, F, G, work)


@kernel
def score_into(
    constants: RowConstants, x: np.ndarray, lateral: bool, lateral_violation: float,
    sequence_violation: float, F: np.ndarray, G: np.ndarray, work: RolloutWork,
) -> float:  # fmt: skip
    """The body of :func:`score_row`, rolling out into the arrays ``work`` of
    :func:`~hcomc.control.prediction.population.rollout_work` (which a population reuses from row to
    row)."""
    c = constants
    plan = np.empty(3)
    plan[0], plan[1], plan[2] = x[0], x[1], x[2]
    _, u_safe, u_eff = rollout_into(c.key, c.starts, plan, lateral, c.consts, c.cf, c.tracks, work)
    fuel = common_distance_fuel(c.cf, c.fuel_roles, work.x, work.v, work.a, c.dt, c.cf_fuel,
                                c.fuel)  # fmt: skip
    objectives_into(u_safe, fuel[0], u_eff, F)
    G[:] = 0.0
    G[:N_G] = work.g
    G[G_LATERAL] = lateral_violation
    G[G_SEQUENCE] = sequence_violation
    return penalised_cost(F, G, c.threshold, c.fuel_ref)


@kernel
def score_rows(
    constants: RowConstants, X: np.ndarray, rows: np.ndarray, lateral: np.ndarray,
    allowed: bool, no_behind: np.ndarray, F: np.ndarray, G: np.ndarray,
) -> None:  # fmt: skip
    """Rows ``rows`` of ``X`` (all of one sequence, whose ``constants`` are as for
    :func:`score_row`) scored into the same rows of ``F`` and ``G``, each by
    :func:`score_row`'s body (``lateral``: per row of ``X``, its mode; ``allowed``: whether
    the sequence admits lateral cooperation; ``no_behind``: per row of ``X``, a "behind" row
    moved ahead for want of a vehicle); the rollout's arrays are allocated once for all
    rows."""
    work = rollout_work(constants.n_steps)
    for q in range(rows.size):
        r = rows[q]
        lat = lateral[r]
        score_into(constants, X[r], lat, 1.0 if lat and not allowed else 0.0,
                   1.0 if no_behind[r] else 0.0, F[r], G[r], work)  # fmt: skip


@functools.cache  # once per process
def load_prediction_kernels() -> None:
    """Load (or compile) the kernels of a decision once per process, so that no timed
    decision pays for it: the rollout (population and single row), U_fuel's and the
    lane-change game's SV simulation."""
    warm_up()
    key, consts, n_steps, cf = warm_up_instant()  # evaluate_row's kernel
    starts = resolve_starts(key.x, key.v, key.params, np.full(N_STARTS, np.nan))
    tracks = vmc_tracks(key, consts, n_steps)
    constants = constants_handle(RowConstants(key, starts, consts, n_steps, cf, tracks,
                                              FUEL_ROLES[1], 0.0, FUEL_COEFFICIENTS, 0.5, 1.0,
                                              1.0))  # fmt: skip
    row, F, G = np.array([800.0, 4.0, 6.0, 0.0, 0.0]), np.empty(3), np.empty(len(CONSTRAINTS))
    score_row(constants, row, False, 0.0, 0.0, F, G)
    rows, lateral = np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.bool_)  # evaluate's
    score_rows(constants, row[None], rows, lateral, True, lateral, F[None], G[None])
    trajectory = np.zeros((1, 2, N_ROLES))
    roles = np.zeros(1, dtype=np.int64)
    _fuel_to_distance_kernel(trajectory, roles, *(trajectory,) * 3, 0.25, FUEL_COEFFICIENTS)
    sv = GameVehicle(x=0.0, v=10.0, length=5.0, desired_speed=30.0, is_cav=True)
    simulate_sv(sv, None, None, IDMParams(), GAME_DEFAULT)
