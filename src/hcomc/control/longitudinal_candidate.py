"""The one longitudinal candidate a rule-based baseline (FIFO, Game) predicts and executes.

The baselines do not optimise the merge (paper Table III): VR changes lane at a fixed position
with the CAV default duration (:func:`merge_position`), and the virtual vehicles' horizon H is
VR's arrival there (:func:`reach_horizon`, refined once from the prediction by
:func:`predict_longitudinal`). The candidate ``[merge_x, vr_duration, H, 0, sequence]`` is
predicted with HCOMC's merge problem (:class:`~hcomc.control.hierarchical.problem.MergeProblem`),
whose ``vv0[0]`` and ``vv1[0]`` are exactly the coefficients the engine executes. When its
virtual vehicles are infeasible, :func:`nearest_feasible` searches a deterministic grid for the
nearest feasible candidate (:func:`feasible_candidate`); :func:`with_cooperation` predicts the
cooperating vehicle yielding or not. The assumptions behind these choices are listed in
:mod:`hcomc.control.fifo`.
"""

from __future__ import annotations

import copy

import numpy as np

from hcomc._typing import FloatArray
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_terms import AHEAD, CONSTRAINTS, Prediction
from hcomc.interface import TrafficView
from hcomc.road import VR

__all__ = [
    "HORIZON_STEP",
    "MERGE_OFFSET",
    "MIN_HORIZON",
    "MIN_SPEED",
    "POSITION_STEP",
    "SEARCH_BLOCK",
    "feasible_candidate",
    "last_merge_position",
    "longitudinal_rows",
    "merge_position",
    "nearest_feasible",
    "predict_longitudinal",
    "reach_horizon",
    "virtual_vehicle_feasible",
    "with_cooperation",
]

MERGE_OFFSET = 10.0
"""VR starts its change this far downstream of the acceleration-lane start [m]."""

MIN_HORIZON = 4.0
"""Lower bound of the virtual-vehicle horizon H [s] (roughly 4-10 s)."""

HORIZON_STEP = 0.5
"""Step of the nearest-feasible search over the virtual-vehicle horizon H [s] (two prediction
steps at the default ``control.prediction_dt``)."""

POSITION_STEP = MERGE_OFFSET
"""Step of the nearest-feasible search over the merge position [m]."""

SEARCH_BLOCK = 16
"""Rows of the nearest-feasible grid scored in its search's first call (then 32, 64, ...).
A grid holds hundreds of candidates and its first feasible one usually lies among the first
few dozen, so the search scores a fraction of the rows it would score all at once."""

MIN_SPEED = 0.1
"""Floor on a speed in the arrival-time predictions [m/s] (no division by zero)."""

_G_VIRTUAL = CONSTRAINTS.index("virtual_vehicle")


def merge_position(view: TrafficView, vr: int) -> tuple[float, float]:
    """Fixed merge position and lane-change duration of VR (no optimisation).

    Parameters
    ----------
    view : traffic snapshot.
    vr : VR's vehicle index.

    Returns
    -------
    merge_x : ``accel_lane_start + 10 m``, clipped to ``accel_lane_end - max(v T, 3 L)`` so the
        change predicted at VR's current speed ends on the acceleration lane, and to at least
        ``accel_lane_start`` [m].
    vr_duration : ``config.cav.lane_change_duration`` [s].
    """
    ramp = view.ramp
    merge_x = min(ramp.accel_lane_start + MERGE_OFFSET, last_merge_position(view, vr))
    return max(merge_x, ramp.accel_lane_start), float(view.config.cav.lane_change_duration)


def last_merge_position(view: TrafficView, vr: int) -> float:
    """The last merge position whose change, predicted at VR's current speed with the CAV
    default duration, ends on the acceleration lane: ``accel_lane_end - max(v T, 3 L)`` [m]
    (the engine's rule, :func:`hcomc.sim.step.lane_change.start_lane_changes`)."""
    duration = float(view.config.cav.lane_change_duration)
    span = max(float(view.v[vr]) * duration, 3.0 * float(view.fleet.length[vr]))
    return float(view.ramp.accel_lane_end - span)


def reach_horizon(view: TrafficView, vr: int, merge_x: float) -> float:
    """VR's constant-speed time to reach ``merge_x``, clipped to ``[4 s, horizon_max]`` [s]."""
    h_max = float(view.config.control.horizon_max)
    t_reach = (merge_x - float(view.x[vr])) / max(float(view.v[vr]), MIN_SPEED)
    return float(np.clip(t_reach, min(MIN_HORIZON, h_max), h_max))


def with_cooperation(problem: MergeProblem, cooperates: bool) -> MergeProblem:
    """Copy of ``problem`` in which the ``vmc`` role (the vehicle behind VR's slot) does or does
    not cooperate (follow VV1), in both sequences.

    The rollout (:func:`hcomc.control.prediction.population.rollout`) makes the VMC role
    follow VV1 iff its ``KeyState.coop`` flag is set, so the flag is overridden on copies of
    the key states (the original problem and the simulation are untouched); the Eq. 15 delays
    still follow the vehicles' true kinds. This idealises an HDV's "yield" as tracking VV1, and
    models "not yield" of a CAV as plain car following.
    """

    ahead, behind = problem.states
    out = copy.copy(problem)
    out.state = ahead.with_vmc_cooperation(cooperates)
    out.states = (out.state, None if behind is None else behind.with_vmc_cooperation(cooperates))
    return out


def predict_longitudinal(
    problem: MergeProblem,
    merge_x: float,
    vr_duration: float,
    horizon: float,
    h_max: float,
    sequence: int = AHEAD,
) -> tuple[Prediction, float]:
    """Predict the candidate ``[merge_x, vr_duration, H, 0, sequence]``, refining H once.

    The first prediction uses ``horizon`` (constant-speed estimate); H is then replaced by the
    predicted time at which VR reaches ``merge_x`` (clipped to ``[4 s, h_max]``) and the
    candidate is predicted again if that differs by more than one prediction step.

    Returns
    -------
    prediction : :class:`~hcomc.control.hierarchical.problem.Prediction` of the single row.
    horizon : the H used [s].
    """
    row = longitudinal_rows(merge_x, horizon, vr_duration, sequence)
    pred = problem.predict(row)
    reached = np.flatnonzero(pred.X[0, :, VR] >= merge_x)
    if reached.size:
        h_new = float(np.clip(pred.t[reached[0]], min(MIN_HORIZON, h_max), h_max))
        if abs(h_new - horizon) > problem.dt:
            horizon = h_new
            row[0, 2] = horizon
            pred = problem.predict(row)
    return pred, float(horizon)


def longitudinal_rows(
    merge_x: FloatArray | float, horizon: FloatArray | float, vr_duration: float, sequence: int
) -> FloatArray:
    """The longitudinal candidate rows ``[merge_x, vr_duration, H, 0, sequence]`` (n, 5) of
    the merge positions ``merge_x`` [m] and horizons ``horizon`` [s] (numbers, or arrays of
    one length)."""
    x, h = np.broadcast_arrays(np.atleast_1d(np.asarray(merge_x, dtype=np.float64)),
                               np.atleast_1d(np.asarray(horizon, dtype=np.float64)))  # fmt: skip
    n = x.size
    rows: FloatArray = np.column_stack(
        [x, np.full(n, float(vr_duration)), h, np.zeros(n), np.full(n, float(sequence))]
    )
    return rows


def virtual_vehicle_feasible(pred: Prediction, row: int = 0) -> bool:
    """Whether the virtual vehicles (VV0 of a CAV VR, VV1 of a cooperating vehicle) of the
    prediction's ``row`` are feasible (v >= 0, a >= -b_max)."""
    return bool(pred.G[row, _G_VIRTUAL] <= 0.0)


def _steps(first: float, last: float, step: float) -> FloatArray:
    """``first, first + step, ...`` up to ``last``, and ``last`` itself (one value if
    ``last <= first``)."""
    n = int(np.floor(max(last - first, 0.0) / step + 1e-9))
    values = first + step * np.arange(n + 1, dtype=np.float64)
    if values[-1] < last:
        values = np.append(values, last)
    out: FloatArray = values
    return out


def nearest_feasible(
    problem: MergeProblem,
    merge_x: float,
    vr_duration: float,
    horizon: float,
    h_max: float,
    x_last: float,
    sequence: int = AHEAD,
) -> tuple[float, float] | None:
    """The candidate nearest to ``(merge_x, horizon)`` whose virtual vehicles are feasible.

    The grid, in the order searched: the merge position ``merge_x`` with H = ``horizon`` +
    k :data:`HORIZON_STEP` (k = 1, 2, ...) and ``h_max``; then each merge position ``merge_x`` +
    i :data:`POSITION_STEP` (i = 1, 2, ...) up to ``x_last`` (and ``x_last`` itself), each with
    H = ``horizon`` + k :data:`HORIZON_STEP` (k = 0, 1, ...) and ``h_max``. The candidates are
    scored by :meth:`MergeProblem.evaluate
    <hcomc.control.hierarchical.problem.MergeProblem.evaluate>` (longitudinal, ``sequence``) in
    that order, :data:`SEARCH_BLOCK` rows at first and twice as many in each next call, until
    a block holds a feasible one: a row's score does not depend on the rows scored beside it,
    so the answer is that of scoring the whole grid at once. Only the virtual-vehicle
    constraint is asked of them, the criterion of the rule's own candidate.

    Returns
    -------
    (merge_x, H) of the first feasible candidate [m, s], or None when none is feasible.
    """
    grid = _search_grid(merge_x, horizon, h_max, x_last)
    start, block = 0, SEARCH_BLOCK
    while start < len(grid):
        cells = grid[start : start + block]
        _, G = problem.evaluate(longitudinal_rows(cells[:, 0], cells[:, 1], vr_duration, sequence))
        ok = np.flatnonzero(G[:, _G_VIRTUAL] <= 0.0)
        if ok.size:
            return float(cells[ok[0], 0]), float(cells[ok[0], 1])
        start, block = start + len(cells), 2 * block
    return None


def _search_grid(merge_x: float, horizon: float, h_max: float, x_last: float) -> FloatArray:
    """The (merge_x, H) cells :func:`nearest_feasible` searches, in its order, (n, 2)."""
    positions = _steps(merge_x, max(x_last, merge_x), POSITION_STEP)
    horizons = _steps(horizon, max(h_max, horizon), HORIZON_STEP)
    grid: FloatArray = np.column_stack(
        (np.repeat(positions, horizons.size), np.tile(horizons, positions.size))
    )
    return grid[1:]  # the rule's own candidate was tried already


def feasible_candidate(
    view: TrafficView,
    vr: int,
    problem: MergeProblem,
    merge_x: float,
    vr_duration: float,
    sequence: int = AHEAD,
) -> tuple[Prediction, float, float, tuple[float, float]]:
    """The rule's candidate (:func:`predict_longitudinal` at the fixed merge position), moved
    to the :func:`nearest_feasible` one when its virtual vehicles are infeasible.

    Returns
    -------
    prediction : of the candidate executed (the rule's own if no candidate is feasible).
    merge_x, horizon : of that candidate [m, s].
    nominal : the rule's own (merge_x, H) [m, s].
    """
    h_max = float(view.config.control.horizon_max)
    pred, horizon = predict_longitudinal(
        problem, merge_x, vr_duration, reach_horizon(view, vr, merge_x), h_max, sequence
    )
    nominal = (merge_x, horizon)
    if virtual_vehicle_feasible(pred):
        return pred, merge_x, horizon, nominal
    found = nearest_feasible(
        problem, merge_x, vr_duration, horizon, h_max, last_merge_position(view, vr), sequence
    )
    if found is None:
        return pred, merge_x, horizon, nominal
    x, h = found
    return problem.predict(longitudinal_rows(x, h, vr_duration, sequence)), x, h, nominal
