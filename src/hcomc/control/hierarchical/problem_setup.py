"""What the HCOMC merge problem prepares for its compiled kernels from the scenario config and
the planning instant, and the loading of those kernels.

:func:`problem_constants` reads the rollout's constants vector from the config,
:data:`FUEL_COEFFICIENTS` are the default fuel model's coefficients, :func:`row_constants` the
record the compiled row scoring (:mod:`~hcomc.control.hierarchical.row_scoring`) takes for one
key group, and :func:`load_prediction_kernels` loads every kernel a decision runs, once per
process. They live here, on the Python side, so that the kernel modules import no config
(whose edit would otherwise recompile them).
"""

from __future__ import annotations

import functools

import numpy as np

from hcomc._typing import FloatArray
from hcomc.config import IDMParams, ScenarioConfig
from hcomc.config.fuel import FUEL_DEFAULT
from hcomc.control.hierarchical import search
from hcomc.control.hierarchical.problem_terms import CONSTRAINTS, KeyState
from hcomc.control.hierarchical.row_scoring import (
    FUEL_ROLES,
    RowConstants,
    constants_handle,
    score_row,
    score_rows_on,
)
from hcomc.control.lane_change_game.params import GAME_DEFAULT
from hcomc.control.lane_change_game.players import GameVehicle, simulate_sv
from hcomc.control.prediction.fuel import _fuel_to_distance_kernel
from hcomc.control.prediction.layout import (
    C_A_MERG,
    C_ACCEL_END,
    C_B_SAFE,
    C_D,
    C_DELAY_CAV,
    C_DELAY_HDV,
    C_DT,
    C_EMERGENCY,
    C_GAMMA,
    C_MIN_GAP,
    C_POLITENESS,
    C_REPLAN,
    C_VMC_DUR,
    C_VV_DECEL,
    C_WIDTH,
    N_CONSTS,
    N_ROLES,
    N_STARTS,
    VMC,
)
from hcomc.control.prediction.population import (
    resolve_starts,
    vmc_tracks,
    warm_up,
    warm_up_instant,
)
from hcomc.equations.fuel import FuelCoefficients
from hcomc.equations.transition import transition_gamma
from hcomc.interface import Ramp
from hcomc.safety.critical import SafetyIndex

__all__ = ["FUEL_COEFFICIENTS", "load_prediction_kernels", "problem_constants", "row_constants"]

FUEL_COEFFICIENTS = FuelCoefficients.of(FUEL_DEFAULT)
"""The default fuel model's coefficients as the kernels take them."""


def problem_constants(config: ScenarioConfig, ramp: Ramp, replanning: bool = False) -> FloatArray:
    """The rollout's constants vector, every value read from ``config`` and the ``ramp``
    (the acceleration lane's end and the lane width).

    ``replanning`` (HCOMC-R: ``control.replan_period > 0``) sets ``C_REPLAN`` to the replan
    period, which turns on the constraints of a replanning controller (the point of no
    return and the engine's execution criterion, ``G_NO_RETURN`` and ``G_EXECUTION``); else
    it is 0 and they stay 0."""
    safety = SafetyIndex.from_config(config.control)
    consts = np.zeros(N_CONSTS)
    consts[C_DT] = config.control.prediction_dt
    consts[C_ACCEL_END] = ramp.accel_lane_end
    consts[C_WIDTH] = ramp.lane_width
    consts[C_VMC_DUR] = config.cav.lane_change_duration
    consts[C_GAMMA] = transition_gamma(config.lane_change.transition_tolerance)
    consts[C_EMERGENCY] = config.lane_change.emergency_decel
    consts[C_VV_DECEL] = config.control.virtual_max_decel
    consts[C_POLITENESS] = config.lane_change.politeness
    consts[C_D] = safety.min_distance
    consts[C_A_MERG] = safety.emergency_decel
    consts[C_DELAY_CAV] = safety.delay_cav
    consts[C_DELAY_HDV] = safety.delay_hdv
    consts[C_REPLAN] = config.control.replan_period if replanning else 0.0
    consts[C_B_SAFE] = config.lane_change.safe_decel  # the engine's: hcomc.sim.step.plans
    consts[C_MIN_GAP] = config.lane_change.min_gap
    return consts


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
    variants, on = (constants,) * 4, np.ones(4, dtype=np.bool_)  # evaluate's
    variant, lateral = np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.bool_)
    for_rows = (*variants, on, on[:2], row[None], variant, lateral, lateral, F[None], G[None])
    score_rows_on(*for_rows, 1)  # its serial and parallel kernels (a main process's decisions)
    search.warm_up(constants)  # NSGA-II's generations on the merge problem
    trajectory = np.zeros((1, 2, N_ROLES))
    roles = np.zeros(1, dtype=np.int64)
    _fuel_to_distance_kernel(trajectory, roles, *(trajectory,) * 3, 0.25, FUEL_COEFFICIENTS)
    sv = GameVehicle(x=0.0, v=10.0, length=5.0, desired_speed=30.0, is_cav=True)
    simulate_sv(sv, None, None, IDMParams(), GAME_DEFAULT)
