"""Lane-change decisions without a merge controller: MOBIL and ramp gap acceptance.

Every candidate names its target lane (on the paper's road: lane 1 -> lane 2 to the left,
lane 2 -> lane 1 to the right, and ramp -> lane 1 on the acceleration lane); what a lane is
and which lane lies to its left the road's lane table says (:mod:`hcomc.sim.lane_table`).
A change out of a ramp lane, or one commanded by a merge plan, is mandatory. For candidate
c, new follower n and old follower o (a tilde means after the change):

* safety: ``ã_n >= -b_safe`` and ``ã_c >= -b_safe``, bumper gaps to the new leader and new
  follower ``>= min_gap`` (MovSim), and a clear path: nobody starts a change towards a
  vehicle standing (< 1 m/s) less than ``3 L + min_gap`` ahead in its own lane, since the
  change takes at least 3 L of road; the ramp's gap acceptance is this criterion alone.
  A change a lane's end or a route needs (urgency u > 0, within ``urgent_distance`` of its
  last point, or past it) may impose ``ã_n >= -(b_safe + u (b_max - b_safe))`` on its new
  follower; the candidate's own ``ã_c >= -b_safe`` stays;
* incentive (discretionary changes only):
  ``ã_c - a_c + p [(ã_n - a_n) + (ã_o - a_o)] > Delta a_th + bias`` to the left and
  ``> Delta a_th - bias`` to the right (keep-right rule).

Accelerations are model accelerations with exact perception (the decision, not the control);
one the simulation step's car following has already taken from the same inputs (a vehicle
behind the same leader, not perceiving Eq. 2: ``Traffic.known``) is reused, the same value.
Simultaneous changes that would meet are resolved so at most one enters each gap: a change is
dropped if its new leader or new follower changes lane in the same round with a higher
priority (ramp vehicles first, then downstream first), or another change with higher priority
targets the same gap. :func:`hcomc.sim.lane_change_decisions.decide` calls these kernels
from Python.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from hcomc._jit import borrow, kernel
from hcomc.equations.car_following import follow_accel_given, free_term
from hcomc.equations.incentive import mobil_incentive
from hcomc.sim.lane_table import KIND_MAIN, L_KIND, L_LEFT, MIN_CHANGE_LENGTHS
from hcomc.sim.neighbours import LaneIndex, lookup_one

LC_MIN_GAP, LC_SAFE_DECEL, LC_POLITENESS, LC_THRESHOLD, LC_BIAS, LC_EMERGENCY_DECEL = range(6)
"""Indices of the lane-change parameters in the array the kernels read
(:func:`hcomc.sim.lane_change_decisions.lane_change_params`)."""


class Traffic(NamedTuple):
    """The vehicles MOBIL judges: their car-following models and kinematic state, each (N,)
    by vehicle index."""

    matrix: np.ndarray  # (7, N) v0 [m/s], T [s], s0 [m], a [m/s^2], b [m/s^2], delta, coolness
    iidm: np.ndarray  # bool: the vehicle drives the IIDM (else the IDM)
    length: np.ndarray  # vehicle length [m]
    x: np.ndarray  # front-bumper position [m]
    v: np.ndarray  # speed [m/s]
    a: np.ndarray  # acceleration [m/s^2]
    known: np.ndarray  # the model acceleration already taken from these exact inputs ...
    known_leader: np.ndarray  # int64: ... behind this leader (-1: free road; NOT_KNOWN: none)


NOT_KNOWN = -2
"""``Traffic.known_leader`` of a vehicle whose model acceleration from exact inputs was not
taken (an HDV that perceives Eq. 2, or a caller that keeps none)."""


class Candidates(NamedTuple):
    """The n candidate lane changes, each (n,)."""

    vehicle: np.ndarray  # int64: the vehicle that would change
    lane: np.ndarray  # int64: its current lane
    leader: np.ndarray  # int64: its leader in that lane (-1: none)
    follower: np.ndarray  # int64: its follower in that lane (-1: none)
    target: np.ndarray  # int64: the lane it would change to
    force: np.ndarray  # bool: commanded by a plan or needed by the route (safety only)
    urgency: np.ndarray  # float64 in [0, 1]: how far a needed change accepts harder braking


class MobilWork(NamedTuple):
    """Work arrays of :func:`mobil_decide_into`, owned by the caller (the simulation step's,
    so that a step allocates nothing)."""

    ints: np.ndarray  # (4, >= n) int64: accepted vehicles, their targets, new leaders, followers
    flags: np.ndarray  # (2, >= n) bool: mandatory change, accepted
    floats: np.ndarray  # (2, >= N) float64: each vehicle's free-road term, its priority
    margin: np.ndarray  # (>= n,) float64: each candidate's incentive above its threshold


@kernel
def mobil_decide_into(
    traffic: Traffic, index: LaneIndex, candidates: Candidates, params: np.ndarray,
    lanes: np.ndarray, work: MobilWork,
) -> int:  # fmt: skip
    """Accepted changes among the n ``candidates`` (see the module docstring), in the
    caller's ``work`` arrays. Returns the number m of accepted changes, whose vehicles and
    targets are ``work.ints[0, :m]`` and ``work.ints[1, :m]``.

    ``params`` = (min_gap, safe_decel, politeness, threshold, keep_right_bias,
    emergency_decel); a candidate's ``urgency`` u lets the change impose up to
    ``safe_decel + u (emergency_decel - safe_decel)``; ``lanes``
    is the road's lane table (:attr:`hcomc.sim.lane_table.LaneTable.ints`); ``index`` holds
    the sorted entries of the snapshot.
    """
    key, lane_of, vehicle = index.key, index.lane, index.vehicle
    matrix, iidm, length, x, v, a, known, known_leader = traffic
    cand, lane, leader, follower, target, force, urgency = candidates
    ints, flags, floats, margin = work
    min_gap, b_safe, politeness = params[LC_MIN_GAP], params[LC_SAFE_DECEL], params[LC_POLITENESS]
    threshold, bias, b_max = params[LC_THRESHOLD], params[LC_BIAS], params[LC_EMERGENCY_DECEL]
    n = cand.size
    new_lead, new_fol = ints[2, :n], ints[3, :n]
    mandatory, ok = flags[0, :n], flags[1, :n]
    kb, lb, vb = borrow(key), borrow(lane_of), borrow(vehicle)
    for k in range(n):
        new_lead[k], new_fol[k] = lookup_one(kb, lb, vb, target[k], x[cand[k]])
    free = floats[0, : x.size]
    free[:] = math.nan  # each vehicle's free-road term, taken once

    def accel(i: int, j: int) -> float:  # a closure: inlined, no call with arrays
        """Model acceleration of i behind j (free road for j = -1; 0 for i = -1)."""
        if i < 0:
            return 0.0
        if known_leader[i] == j:  # taken this step behind j from these inputs
            return known[i]
        if j >= 0:
            s, vl, al = x[j] - length[j] - x[i], v[j], a[j]
        else:
            s, vl, al = math.inf, v[i], 0.0
        if math.isnan(free[i]):
            free[i] = free_term(v[i], matrix[0, i], matrix[3, i], matrix[4, i], matrix[5, i],
                                iidm[i])  # fmt: skip
        return follow_accel_given(
            s, v[i], vl, al, matrix[0, i], matrix[1, i], matrix[2, i], matrix[3, i],
            matrix[4, i], matrix[6, i], iidm[i], free[i],
        )  # fmt: skip

    for k in range(n):
        ok[k] = False
        c, lo, ln, fn, fo = cand[k], leader[k], new_lead[k], new_fol[k], follower[k]
        mandatory[k] = lanes[L_KIND, lane[k]] != KIND_MAIN or force[k]
        if not _gaps_clear(x, v, length, c, lo, ln, fn, min_gap):  # 1. needing no model
            continue
        # 2. the deceleration criteria: candidate and new follower after the change
        acc1, acc3 = accel(c, ln), accel(fn, c)
        b_ok = b_safe + (b_max - b_safe) * urgency[k]  # what it may impose on its follower
        if not (acc1 >= -b_safe and acc3 >= -b_ok):
            continue
        if mandatory[k]:
            ok[k], margin[k] = True, math.inf
            continue
        # 3. the incentive of a discretionary change
        acc0, acc2, acc4, acc5 = accel(c, lo), accel(fn, ln), accel(fo, c), accel(fo, lo)
        gain = mobil_incentive(acc1 - acc0, (acc3 - acc2) + (acc5 - acc4), politeness)
        side = bias if target[k] == lanes[L_LEFT, lane[k]] else -bias
        margin[k] = gain - (threshold + side)
        ok[k] = margin[k] > 0.0
    _better_of_two(cand[:n], ok, margin[:n])
    ids, targets = ints[0], ints[1]
    m = 0
    for k in range(n):  # the accepted, in order (m <= k: the rows are compacted in place)
        if ok[k]:
            ids[m], targets[m] = cand[k], target[k]
            new_lead[m], new_fol[m], mandatory[m] = new_lead[k], new_fol[k], mandatory[k]
            m += 1
    return _resolve_into(ids[:m], targets[:m], new_lead[:m], new_fol[:m], mandatory[:m], x,
                         floats[1, : x.size], ok[:m])  # fmt: skip


@kernel(inline="always")
def _gaps_clear(
    x: np.ndarray, v: np.ndarray, length: np.ndarray, c: int, lo: int, ln: int, fn: int,
    min_gap: float,
) -> bool:  # fmt: skip
    """The gap criteria of candidate c's change (module docstring): bumper gaps of at least
    ``min_gap`` to its new leader ``ln`` and new follower ``fn``, and a clear path past its
    leader ``lo`` if that is standing (-1: none)."""
    s_o = _gap(x[c], x[lo], length[lo], lo >= 0)
    s_c = _gap(x[c], x[ln], length[ln], ln >= 0)
    s_n = _gap(x[fn], x[c], length[c], fn >= 0)
    standing = lo >= 0 and v[lo] < 1.0
    clear = not standing or s_o >= MIN_CHANGE_LENGTHS * length[c] + min_gap
    return clear and s_c >= min_gap and s_n >= min_gap


@kernel(inline="always")
def _better_of_two(cand: np.ndarray, ok: np.ndarray, margin: np.ndarray) -> None:
    """Of two accepted candidates of one vehicle (adjacent rows: its changes to the left
    and to the right), keep the one with the larger incentive margin (the first on a tie)."""
    for k in range(1, cand.size):
        if ok[k] and ok[k - 1] and cand[k] == cand[k - 1]:
            if margin[k] > margin[k - 1]:
                ok[k - 1] = False
            else:
                ok[k] = False


@kernel(inline="always")
def _gap(x_i: float, x_j: float, length_j: float, exists: bool) -> float:
    """Bumper gap [m] of a vehicle at ``x_i`` to one at ``x_j`` ahead of it, inf if there is
    none (numbers, not arrays: called for every candidate)."""
    return x_j - length_j - x_i if exists else math.inf


@kernel
def _resolve(
    ids: np.ndarray, target: np.ndarray, new_lead: np.ndarray, new_fol: np.ndarray,
    mandatory: np.ndarray, x: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Drop changes that conflict with a higher-priority change of the same round:
    ``(vehicles, targets)`` kept (:func:`_resolve_into` on copies)."""
    ids, target = ids.copy(), target.copy()
    m = _resolve_into(ids, target, new_lead, new_fol, mandatory, x, np.empty(x.size),
                      np.empty(ids.size, dtype=np.bool_))  # fmt: skip
    return ids[:m], target[:m]


@kernel
def _resolve_into(
    ids: np.ndarray, target: np.ndarray, new_lead: np.ndarray, new_fol: np.ndarray,
    mandatory: np.ndarray, x: np.ndarray, priority: np.ndarray, keep: np.ndarray,
) -> int:  # fmt: skip
    """Drop changes that conflict with a higher-priority change of the same round, in place:
    the m kept are ``ids[:m]``, ``target[:m]``, in order. ``priority`` (N,) and ``keep``
    (as long as ``ids``) are work arrays."""
    if ids.size <= 1:
        return ids.size
    # priority: ramp vehicles first, then further downstream first
    priority[:] = -np.inf
    for k in range(ids.size):
        priority[ids[k]] = mandatory[k] * 1e9 + x[ids[k]]
    for k in range(ids.size):
        mine = priority[ids[k]]
        lead = new_lead[k] if new_lead[k] >= 0 else ids[k]
        fol = new_fol[k] if new_fol[k] >= 0 else ids[k]
        beaten = priority[lead] > mine or priority[fol] > mine
        # two changes into the same gap (same target lane, same new follower): keep the best
        for m in range(ids.size):
            if m != k and target[m] == target[k] and new_fol[m] == new_fol[k]:
                other = priority[ids[m]]
                if other > mine or (other == mine and m < k):
                    beaten = True
        keep[k] = not beaten
    m = 0
    for k in range(ids.size):
        if keep[k]:
            ids[m], target[m] = ids[k], target[k]
            m += 1
    return m
