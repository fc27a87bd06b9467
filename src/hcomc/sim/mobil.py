"""Lane-change decisions without a merge controller: MOBIL and ramp gap acceptance.

Every candidate has exactly one possible target lane: lane 1 -> lane 2 (to the left),
lane 2 -> lane 1 (to the right) and ramp -> lane 1 on the acceleration lane. For candidate c,
new follower n and old follower o (a tilde means after the change):

* safety: ``ã_n >= -b_safe`` and ``ã_c >= -b_safe``, bumper gaps to the new leader and new
  follower ``>= min_gap`` (MovSim), and a clear path: nobody starts a change towards a
  vehicle standing (< 1 m/s) less than ``3 L + min_gap`` ahead in its own lane, since the
  change takes at least 3 L of road; the ramp's gap acceptance is this criterion alone;
* incentive (discretionary changes only):
  ``ã_c - a_c + p [(ã_n - a_n) + (ã_o - a_o)] > Delta a_th + bias`` to the left and
  ``> Delta a_th - bias`` to the right (keep-right rule).

Accelerations are model accelerations with exact perception (the decision, not the control).
Simultaneous changes that would meet are resolved so at most one enters each gap: a change is
dropped if its new leader or new follower changes lane in the same round with a higher
priority (ramp vehicles first, then downstream first), or another change with higher priority
targets the same gap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import LaneChangeParams
from hcomc.road import Lane
from hcomc.sim.fleet import Fleet, follow
from hcomc.sim.neighbours import LaneIndex


@dataclass(frozen=True, slots=True)
class Snapshot:
    """Read-only kinematic state of all vehicle slots, shape (N,) each."""

    x: FloatArray
    v: FloatArray
    a: FloatArray


def _gap_accel(
    fleet: Fleet, snap: Snapshot, ids: IntArray, leader: IntArray
) -> tuple[FloatArray, FloatArray]:
    """Gap of ``ids`` to ``leader`` (inf for -1) and their model acceleration behind it."""
    has = leader >= 0
    lead = np.where(has, leader, 0)
    s = np.where(has, snap.x[lead] - fleet.length[lead] - snap.x[ids], np.inf)
    vl = np.where(has, snap.v[lead], snap.v[ids])
    al = np.where(has, snap.a[lead], 0.0)
    return s, follow(fleet, ids, s, snap.v[ids], vl, al)


def decide(
    fleet: Fleet,
    snap: Snapshot,
    index: LaneIndex,
    cand: IntArray,
    lane: IntArray,
    leader: IntArray,
    follower: IntArray,
    params: LaneChangeParams,
    target: IntArray | None = None,
    force: BoolArray | None = None,
) -> tuple[IntArray, IntArray]:
    """Accepted lane changes among candidates ``cand``: ``(vehicles, target lanes)``.

    ``lane``, ``leader`` and ``follower`` are the candidates' current lane and neighbours.
    ``target`` defaults to the one possible target of each lane; ``force`` marks changes
    commanded by a merge plan, which are checked for safety only (like the ramp's).
    """
    if cand.size == 0:
        return cand, cand
    if target is None:
        target = np.where(lane == Lane.MAIN_1, Lane.MAIN_2, Lane.MAIN_1)
    new_lead, new_fol = index.lookup(target, snap.x[cand])
    # all situations in one vectorised call, rows: candidate before/after, new follower
    # before/after, old follower before/after (-1 followers are masked afterwards)
    followers = np.concatenate([cand, cand, new_fol, new_fol, follower, follower])
    leaders = np.concatenate([leader, new_lead, new_lead, cand, cand, leader])
    present = followers >= 0
    s, acc = _gap_accel(fleet, snap, np.where(present, followers, 0), leaders)
    s = np.where(present, s, np.inf).reshape(6, cand.size)
    acc = np.where(present, acc, 0.0).reshape(6, cand.size)
    s_o, s_c, s_n = s[0], s[1], s[3]
    a_c_new, a_n_new = acc[1], acc[3]
    gain_c, gain_n, gain_o = acc[1] - acc[0], acc[3] - acc[2], acc[5] - acc[4]
    standing = (leader >= 0) & (snap.v[np.where(leader >= 0, leader, 0)] < 1.0)
    clear = ~standing | (s_o >= 3.0 * fleet.length[cand] + params.min_gap)
    safe = (
        clear
        & (s_c >= params.min_gap)
        & (s_n >= params.min_gap)
        & (a_n_new >= -params.safe_decel)
        & (a_c_new >= -params.safe_decel)
    )
    gain = gain_c + params.politeness * (gain_n + gain_o)
    bias = np.where(target == Lane.MAIN_2, params.keep_right_bias, -params.keep_right_bias)
    mandatory = lane == Lane.RAMP
    if force is not None:
        mandatory = mandatory | force
    ok = safe & (mandatory | (gain > params.threshold + bias))
    return _resolve(cand[ok], target[ok], new_lead[ok], new_fol[ok], mandatory[ok], snap.x)


def _resolve(
    ids: IntArray,
    target: IntArray,
    new_lead: IntArray,
    new_fol: IntArray,
    mandatory: BoolArray,
    x: FloatArray,
) -> tuple[IntArray, IntArray]:
    """Drop changes that conflict with a higher-priority change of the same round."""
    if ids.size <= 1:
        return ids, target
    # priority: ramp vehicles first, then further downstream first
    priority = np.empty(x.size)
    priority.fill(-np.inf)
    priority[ids] = mandatory * 1e9 + x[ids]
    mine = priority[ids]
    beaten = (priority[np.where(new_lead >= 0, new_lead, ids)] > mine) | (
        priority[np.where(new_fol >= 0, new_fol, ids)] > mine
    )
    # two changes into the same gap (same target lane and same new follower): keep the best
    gap_key = target * (x.size + 1) + (new_fol + 1)
    order = np.lexsort((-mine, gap_key))
    first = np.ones(ids.size, dtype=bool)
    first[order[1:]] = gap_key[order[1:]] != gap_key[order[:-1]]
    keep = ~beaten & first
    return ids[keep], target[keep]
