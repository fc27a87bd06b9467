"""Eq. 15's safety index realised at VR's merge completion (:func:`u_safe_at_merge`): the
planner's safety objective (:mod:`hcomc.control.prediction.scoring`) evaluated on the logged
run, for the pair the merge creates behind VR.
"""

from __future__ import annotations

import math

from hcomc.config import ControlParams
from hcomc.equations.safety import critical_accel
from hcomc.metrics.leaders import lane_follower
from hcomc.metrics.window import MetricWindow, post_merge_rows, recorded_section
from hcomc.road import Kind, Lane
from hcomc.safety.critical import SafetyIndex
from hcomc.sim.log import SimulationLog

__all__ = ["safety_index_of", "u_safe_at_merge"]


def safety_index_of(log: SimulationLog) -> SafetyIndex:
    """The Eq. 15 parameters of the run (``log.meta["config"]["control"]``), as the planner
    reads them (:meth:`hcomc.safety.critical.SafetyIndex.from_config`).

    Raises
    ------
    ValueError
        If the log's metadata holds no control section.
    """
    control = recorded_section(log, "control", "the control parameters")
    return SafetyIndex.from_config(ControlParams.model_validate(control))


def u_safe_at_merge(log: SimulationLog, window: MetricWindow) -> float:
    """Eq. 15's safety index ``U_safe`` realised at VR's merge completion [m/s²] (smaller is
    better).

    Definition: in the first logged row with ``t >= max(t_merge, t_start)`` (the row of VR's
    MERGE event: the engine stamps a step's events with its start time, so with logging
    every step this row holds the state at the start of the step in which VR's lane change
    ends, VR logged in lane 1 from half-way), VR is the leader and its new follower f the
    vehicle just behind it in lane 1 (:func:`hcomc.metrics.leaders.lane_follower`: any
    vehicle, key or not, VR counted in lane 1). ``U_safe = a_cr`` of paper Eq. 15 with the
    function the planner evaluates, :func:`hcomc.equations.safety.critical_accel`, and its
    arguments as the planner gives them for this pair
    (:func:`hcomc.control.prediction.scoring.created_pairs_safety`, which also takes VR
    behind its own leader and the lateral-mode pairs, and keeps the largest): gap
    ``d = x_VR - L_VR - x_f`` [m], ``v_r`` the follower's speed, ``v_f`` VR's speed [m/s],
    delay ``T`` of the follower's kind (CAV: ``control.safety_delay_cav``, HDV:
    ``control.safety_delay_hdv``), ``D = control.safety_min_distance`` and
    ``a_merg = control.safety_emergency_decel`` (:func:`safety_index_of`):

    ``U_safe = v_r² / (2 (d - D - v_r T + v_f² / (2 a_merg)))``

    the constant deceleration the follower needs, after its delay, to stop ``D`` behind VR
    braking at ``a_merg``. The planner's gate (Eq. 19) is ``U_safe <= 4 m/s²``.

    Returns
    -------
    float
        ``U_safe`` [m/s²]; ``inf`` if no deceleration avoids the crash (Eq. 15's
        denominator not positive). NaN if VR did not merge, merged after the last logged
        row or is inactive in that row, or has no follower in lane 1 there.
    """
    vr = window.vr
    if vr < 0 or not window.merged:
        return math.nan
    rows = post_merge_rows(log, window)
    if rows.stop <= rows.start:
        return math.nan
    row = rows.start
    follower = lane_follower(log, row, vr, int(Lane.MAIN_1))
    if follower < 0:
        return math.nan
    safety = safety_index_of(log)
    is_cav = int(log.kind[follower]) == int(Kind.CAV)
    delay = safety.delay_cav if is_cav else safety.delay_hdv
    gap = float(log.x[row, vr]) - float(log.length[vr]) - float(log.x[row, follower])
    v_rear, v_front = float(log.v[row, follower]), float(log.v[row, vr])
    return float(critical_accel(gap, v_rear, v_front, delay, safety.min_distance,
                                safety.emergency_decel))  # fmt: skip
