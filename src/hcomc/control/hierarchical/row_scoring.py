"""The compiled scoring of candidate rows of the merge problem, one row at a time.

:meth:`MergeProblem.evaluate <hcomc.control.hierarchical.problem.MergeProblem.evaluate>` (a
population) and :meth:`~hcomc.control.hierarchical.problem.MergeProblem.evaluate_row` (simulated
annealing's single rows) score each row in one compiled body (:func:`score_into`): its rollout,
U_fuel, the objectives, the constraints and the penalised cost, on constants prepared once per
planning instant and variant (sequence and mode "none",
:func:`~hcomc.control.hierarchical.problem_setup.row_constants`), as does NSGA-II's compiled
search (:mod:`~hcomc.control.hierarchical.search`). No population of
trajectories is allocated and the values equal those of :meth:`MergeProblem.predict
<hcomc.control.hierarchical.problem.MergeProblem.predict>` bit for bit.
:func:`~hcomc.control.hierarchical.problem_setup.load_prediction_kernels` loads these kernels,
and the others a decision needs, once per process. What is read from the config (the fuel
model, the game's parameters) is prepared there, beside the problem, so that these kernels'
cache depends on the kernels alone.

A population's rows are independent, so :func:`score_rows` scores them on every core of a
main process and on one in a worker process (:func:`scoring_threads`); each row's values are
the same bit for bit either way.

The constants are a :class:`RowConstants` record, which the kernels receive through its
compiled handle (:func:`constants_handle`), as the engine's step receives its ``CoreArrays``
through ``Core`` (:mod:`hcomc.sim.step.state`): numba types a record argument anew at every
call from Python, reading the names of its fields and of the fields of the records in it,
which would cost simulated annealing a few microseconds per row; a handle costs one
pointer.
"""

from __future__ import annotations

import multiprocessing
import threading
from typing import Any, NamedTuple

import numba
import numpy as np
from numba import prange
from numba.core import types
from numba.experimental import structref

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.control.hierarchical.problem_terms import G_LATERAL, G_SEQUENCE
from hcomc.control.prediction.candidate import RolloutWork
from hcomc.control.prediction.fuel import FuelCoefficients, common_distance_fuel
from hcomc.control.prediction.layout import N_G
from hcomc.control.prediction.population import VMC, VR, KeyVehicles, rollout_into, rollout_work
from hcomc.control.prediction.scoring import objectives_into, penalised_cost

__all__ = [
    "FUEL_ROLES",
    "RowConstants",
    "RowConstantsRef",
    "constants_handle",
    "score_into",
    "score_row",
    "score_rows",
    "score_rows_on",
    "score_rows_parallel",
    "score_rows_serial",
    "scoring_threads",
]

FUEL_ROLES = (np.array([VR], dtype=np.int64), np.array([VR, VMC], dtype=np.int64))
"""U_fuel's roles: VR alone, or VR and the cooperating vehicle (indexed by its presence)."""


class RowConstants(NamedTuple):
    """What the scoring of a row (:func:`score_row`) takes from its problem: the values that
    depend on the planning instant and the key group alone, prepared once per problem and
    sequence (:func:`~hcomc.control.hierarchical.problem_setup.row_constants`)."""

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
    G[:N_G] = work.g  # the kernel's columns (the problem's two are 0 there)
    G[G_LATERAL] = lateral_violation
    G[G_SEQUENCE] = sequence_violation
    return penalised_cost(F, G, c.threshold, c.fuel_ref)


@kernel(inline="always")
def _score_part(
    variants: tuple[RowConstants, ...], scored: np.ndarray, allowed: np.ndarray, X: np.ndarray,
    variant: np.ndarray, lateral: np.ndarray, no_behind: np.ndarray, F: np.ndarray,
    G: np.ndarray, part: int, n_parts: int, work: RolloutWork,
) -> None:  # fmt: skip
    """Rows ``part::n_parts`` of ``X`` scored into the same rows of ``F`` and ``G`` by
    :func:`score_into`, rolling out into ``work`` (arguments of :func:`score_rows`)."""
    for r in range(part, X.shape[0], n_parts):
        v = variant[r]
        if not scored[v]:
            continue
        lat = lateral[r]
        score_into(variants[v], X[r], lat, 1.0 if lat and not allowed[v % 2] else 0.0,
                   1.0 if no_behind[r] else 0.0, F[r], G[r], work)  # fmt: skip


@kernel
def score_rows_serial(
    ahead: RowConstants, behind: RowConstants, ahead_none: RowConstants,
    behind_none: RowConstants, scored: np.ndarray, allowed: np.ndarray, X: np.ndarray,
    variant: np.ndarray, lateral: np.ndarray, no_behind: np.ndarray, F: np.ndarray,
    G: np.ndarray,
) -> None:  # fmt: skip
    """:func:`score_rows` on the calling thread, the rollout's arrays allocated once for all
    rows. The variants' constants come one by one (numba types a tuple of handles from
    Python at every call, 10 us) and are gathered here."""
    variants = (ahead, behind, ahead_none, behind_none)
    work = rollout_work(ahead.n_steps)
    _score_part(variants, scored, allowed, X, variant, lateral, no_behind, F, G, 0, 1, work)


@kernel(parallel=True)
def score_rows_parallel(
    ahead: RowConstants, behind: RowConstants, ahead_none: RowConstants,
    behind_none: RowConstants, scored: np.ndarray, allowed: np.ndarray, X: np.ndarray,
    variant: np.ndarray, lateral: np.ndarray, no_behind: np.ndarray, F: np.ndarray,
    G: np.ndarray, n_parts: int,
) -> None:  # fmt: skip
    """:func:`score_rows` on ``n_parts`` threads (``numba.prange``): part p scores rows p,
    p + n_parts, ... with rollout arrays of its own. A function of its own, not
    :func:`score_rows_serial` compiled twice: numba's cache keys an entry by the function
    and its signature, not by ``parallel``."""
    variants = (ahead, behind, ahead_none, behind_none)
    for part in prange(n_parts):
        work = rollout_work(ahead.n_steps)
        _score_part(variants, scored, allowed, X, variant, lateral, no_behind, F, G, part,
                    n_parts, work)  # fmt: skip


@kernel
def score_rows_on(
    ahead: RowConstants, behind: RowConstants, ahead_none: RowConstants,
    behind_none: RowConstants, scored: np.ndarray, allowed: np.ndarray, X: np.ndarray,
    variant: np.ndarray, lateral: np.ndarray, no_behind: np.ndarray, F: np.ndarray,
    G: np.ndarray, n_parts: int,
) -> None:  # fmt: skip
    """:func:`score_rows` on ``n_parts`` threads: :func:`score_rows_parallel` for more than
    one, else :func:`score_rows_serial` (which alone runs where parallel kernels must not)."""
    args = (ahead, behind, ahead_none, behind_none, scored, allowed, X, variant, lateral,
            no_behind, F, G)  # fmt: skip
    if n_parts > 1:
        score_rows_parallel(*args, n_parts)
    else:
        score_rows_serial(*args)


def scoring_threads() -> int:
    """The threads a population's rows are scored on: numba's (every core, unless
    ``NUMBA_NUM_THREADS`` or :func:`numba.set_num_threads` says fewer) on a main process's main
    thread; one in a worker process (hcomc's run pools, a user's ``multiprocessing`` or Dask
    workers), whose siblings take the other cores, and on any other thread (numba's
    ``workqueue`` layer, its fallback, cannot run two parallel kernels at once)."""
    if multiprocessing.parent_process() is not None:
        return 1
    if threading.current_thread() is not threading.main_thread():
        return 1
    return int(numba.get_num_threads())


def score_rows(
    variants: tuple[RowConstants, ...], scored: BoolArray, allowed: BoolArray, X: FloatArray,
    variant: IntArray, lateral: BoolArray, no_behind: BoolArray, F: FloatArray, G: FloatArray,
) -> None:  # fmt: skip
    """The rows of ``X`` scored into the same rows of ``F`` and ``G``, each by
    :func:`score_row`'s body in its variant, on :func:`scoring_threads` threads, in one
    compiled call.

    ``variants``: the :class:`RowConstants` handles of the problem's four variants (sequence
    + 2 for the mode "none"; every variant's n_steps the same), of which those with ``scored``
    true are scored (the others' rows are left as they are); ``allowed``: per sequence,
    whether it admits lateral cooperation; per row of ``X``: its ``variant``, its mode
    (``lateral``) and whether it is a "behind" row moved ahead for want of a vehicle
    (``no_behind``).

    A row's values depend on its own inputs alone, so they are the same bit for bit
    whatever the number of threads."""
    ahead, behind, ahead_none, behind_none = variants
    score_rows_on(ahead, behind, ahead_none, behind_none, scored, allowed, X, variant, lateral,
                  no_behind, F, G, min(scoring_threads(), X.shape[0]))  # fmt: skip
