"""The per-step work of an episode as compiled kernels: the agent's action, and after the
runs advanced, the observation and the reward's terms. One episode
(:class:`~hcomc.envs.episode.MergeEpisode`) calls them one at a time; the vector environment
calls them for all its episodes at once, so a step of 64 environments costs a few Python
calls instead of a few hundred.

They read the runs' compiled state (:class:`hcomc.sim.step.state.Core`: positions, the
log rows, the event counters) and call the one home of each equation; what the terms make of
a step (its outcome and reward) is :mod:`hcomc.envs.scoring`'s.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc.envs.observation import SafetyParams, Scene, observe, pair_safety
from hcomc.envs.reward import fuel_over_rows, gain_over_rows
from hcomc.road import VMC, VMR, VNR
from hcomc.sim.lane_table import KIND_MAIN, L_END, L_KIND, L_OPENS
from hcomc.sim.log.slots import rows_of
from hcomc.sim.step.lane_change import free_target, start_lane_changes
from hcomc.sim.step.ramp_reach import ramp_may_reach, ramp_untouched
from hcomc.sim.step.state import (
    COLLISIONS,
    DT,
    ROWS,
    STEP,
    WARMUP,
    CoreArrays,
    command,
)

# the episode parameters the kernels read, in one float64 vector
# (see hcomc.envs.scoring.parameters)
P_ACCEL_START, P_ACCEL_END, P_EMERGENCY, P_DELAY_CAV, P_DELAY_HDV, P_MIN_DIST = range(6)
P_A_MERG, P_PERIOD, P_LOG_DT, P_ETA, P_FUEL = range(6, 11)
N_TERMS = 9
"""Columns of a step's terms: safety, fuel, efficiency, merged, at lane end, collisions so
far, log rows so far, VR on the road, time [s]."""
T_SAFETY, T_FUEL, T_EFFICIENCY, T_MERGED, T_LANE_END, T_COLLISIONS, T_ROWS = range(7)
T_VR_ON_ROAD, T_TIME = 7, 8


@kernel
def apply_one(c: CoreArrays, i: int, accel: float, change: float, p: np.ndarray) -> None:
    """Drive vehicle i with an action (see :func:`hcomc.envs.episode.apply_action`)."""
    a = min(max(accel, -1.0), 1.0)
    limit = c.matrix[3, i] if a >= 0 else p[P_EMERGENCY]  # its a_max, or the emergency
    command(c, i, a * limit)
    if change <= 0 or c.origin[i] != c.target[i] or not c.active[i]:
        return
    lane = c.lane[i]
    ramp = c.road_int[L_KIND, lane] != KIND_MAIN
    if ramp and not c.road_f[L_OPENS, lane] <= c.x[i] <= c.road_f[L_END, lane]:
        return
    target = free_target(c.road_int, lane)
    if target < 0:
        return
    t = -c.consts[WARMUP] + c.counters[STEP] * c.consts[DT]
    start_lane_changes(c, np.array([i]), np.array([target]), t, np.array([math.nan]))


@kernel
def _is_ramp(c: CoreArrays, i: int) -> bool:
    """Whether vehicle i came from a ramp (is in a ramp lane's release queue)."""
    for lane in range(c.queue_pos.size):
        if c.road_int[L_KIND, lane] != KIND_MAIN:
            queue = c.queues[c.queue_start[lane] : c.queue_start[lane + 1]]
            if np.any(queue == i):
                return True
    return False


@kernel(inline="always")
def _rows(c: CoreArrays, store: np.ndarray, i: int, r0: int, r1: int) -> np.ndarray:
    """Vehicle i's cells of one of run ``c``'s log columns over rows ``[r0, r1)``."""
    return rows_of(store, c.log_slot, c.log_span, i, r0, r1)


@kernel
def step_terms(
    c: CoreArrays, ref: CoreArrays, ego: int, vr: int, r0: int, p: np.ndarray, out: np.ndarray,
    terms: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """Observation (into ``out``) and reward terms (into ``terms``, see :data:`N_TERMS`) of
    one episode after its run ``c`` and undisturbed twin ``ref`` advanced one period from
    log row ``r0``; returns the key vehicles. Eq. 15 of the agent's pairs (normalised, times
    the period), Eq. 16 of VR and VMC, Eq. 17 of VR (against its free road) plus eta times
    that of VMC, VMR and VNR (against the twin)."""
    is_cav = np.logical_not(c.is_hdv)
    scene = Scene(c.x, c.v, c.lane, c.active, is_cav, c.length, c.origin, c.target, c.lc_x0,
                  c.lc_xf)  # fmt: skip
    group = observe(out, scene, ego, vr, p[P_ACCEL_END])
    terms[T_SAFETY] = p[P_PERIOD] * pair_safety(
        scene, ego, SafetyParams(p[P_DELAY_CAV], p[P_DELAY_HDV], p[P_MIN_DIST], p[P_A_MERG])
    )
    r1 = c.counters[ROWS]
    fuel, own, others = 0.0, 0.0, 0.0
    if r1 > r0:
        coefs = p[P_FUEL:]
        for i in (vr, group[VMC]):
            if i >= 0:
                fuel += fuel_over_rows(_rows(c, c.log_v, i, r0, r1), _rows(c, c.log_a, i, r0, r1),
                                       p[P_LOG_DT], coefs)  # fmt: skip
        for r in range(4):
            i = vr if r == 0 else group[(VMC, VMR, VNR)[r - 1]]
            if i < 0:
                continue
            g = gain_over_rows(_rows(c, c.log_v, i, r0, r1), _rows(c, c.log_a, i, r0, r1),
                               _rows(ref, ref.log_a, i, r0, r1), p[P_LOG_DT], _is_ramp(c, i),
                               c.matrix[:, i], c.iidm[i])  # fmt: skip
            if r == 0:
                own = g
            else:
                others += g
    terms[T_FUEL], terms[T_EFFICIENCY] = fuel, own + p[P_ETA] * others
    keeping = c.origin[vr] == c.target[vr]
    on_ramp = c.road_int[L_KIND, c.lane[vr]] != KIND_MAIN
    terms[T_MERGED] = 1.0 if not on_ramp and keeping else 0.0
    at_end = on_ramp and keeping and c.x[vr] >= c.road_f[L_END, c.lane[vr]]
    terms[T_LANE_END] = 1.0 if at_end else 0.0
    terms[T_COLLISIONS] = c.counters[COLLISIONS]
    terms[T_ROWS] = r1
    terms[T_VR_ON_ROAD] = 1.0 if c.active[vr] else 0.0
    terms[T_TIME] = -c.consts[WARMUP] + c.counters[STEP] * c.consts[DT]  # as Simulation.t
    return group


@kernel
def step_terms_batch(
    cores: list[CoreArrays], refs: list[CoreArrays], egos: np.ndarray, vrs: np.ndarray,
    r0s: np.ndarray, p: np.ndarray, obs: np.ndarray, terms: np.ndarray, groups: np.ndarray,
) -> None:  # fmt: skip
    """:func:`step_terms` of every episode (rows of ``obs``, ``terms`` and ``groups``)."""
    for k in range(len(cores)):
        groups[k] = step_terms(cores[k], refs[k], egos[k], vrs[k], r0s[k], p, obs[k], terms[k])


@kernel
def apply_batch(
    cores: list[CoreArrays], egos: np.ndarray, actions: np.ndarray, drive: np.ndarray,
    p: np.ndarray,
) -> None:  # fmt: skip
    """:func:`apply_one` for every episode whose ``drive`` flag is set."""
    for k in range(len(cores)):
        if drive[k]:
            apply_one(cores[k], egos[k], actions[k, 0], actions[k, 1], p)


@kernel
def twins_due(
    cores: list[CoreArrays], pending: np.ndarray, horizon: float, out: np.ndarray
) -> None:
    """:func:`~hcomc.sim.step.ramp_reach.ramp_may_reach` within ``horizon`` [s] of every run whose
    ``pending`` flag is set (False for the others)."""
    for k in range(len(cores)):
        out[k] = pending[k] and ramp_may_reach(cores[k], horizon)


@kernel
def ramps_untouched(cores: list[CoreArrays], pending: np.ndarray, out: np.ndarray) -> None:
    """:func:`~hcomc.sim.step.ramp_reach.ramp_untouched` of every run whose ``pending`` flag is set
    (False for the others)."""
    for k in range(len(cores)):
        out[k] = pending[k] and ramp_untouched(cores[k])
