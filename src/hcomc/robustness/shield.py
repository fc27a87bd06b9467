"""The safety shield: an RSS safe-distance rule checked before a command acts.

Responsibility-Sensitive Safety (Shalev-Shwartz, Shammah & Shashua 2017, "On a Formal
Model of Safe and Scalable Self-driving Cars", Definition 1): a rear vehicle at speed
``v_r`` is at a safe distance behind a front vehicle at ``v_f`` if, when the front vehicle
brakes at up to ``b_max`` and the rear one accelerates at up to ``a_max`` during its response
time ``rho`` and then brakes at least ``b_min``, they do not touch.

The shield runs between two steps of a run on the true state. For every vehicle a live plan
commands (:meth:`hcomc.interface.listener.ListenedRun.commanded`) and every lane its body
occupies, it checks the distance to the nearest vehicle ahead; closer than
:func:`rss_safe_distance`, the vehicle brakes for the next step at ``min(its car-following
acceleration behind that vehicle, -b_min)`` (RSS's proper response), which replaces the
plan's command. A commanded lane change of VR is gated the same way, before it starts:
against the target lane's leader (VR behind) and follower (VR ahead); unsafe, the change
waits a step (:meth:`~hcomc.interface.listener.ListenedRun.hold_merge`), and if VR could no
longer stop before the lane end it is released to gap acceptance
(:meth:`~hcomc.interface.listener.ListenedRun.release_merge`). Every override is recorded.
Both engines offer these levers, so the same shield runs on either.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.config import ScenarioConfig
from hcomc.config.impairment_tables import ShieldParams
from hcomc.equations.safety import stopping_distance
from hcomc.interface.listener import ListenedRun
from hcomc.interface.ramp import ramp_in
from hcomc.robustness.run_state import DrivenVehicles

__all__ = ["Override", "Shield", "rss_safe_distance"]


def rss_safe_distance(
    v_rear: FloatArray | float, v_front: FloatArray | float, response_time: float,
    accel_max: float, brake_min: float, brake_max: float,
) -> FloatArray:  # fmt: skip
    """Minimal safe longitudinal distance [m] (RSS Definition 1):

    ``[v_r rho + a_max rho^2 / 2 + (v_r + rho a_max)^2 / (2 b_min) - v_f^2 / (2 b_max)]_+``

    Parameters: speeds [m/s] (arrays broadcast), ``response_time`` rho [s], ``accel_max``
    [m/s^2] (the rear vehicle's worst acceleration during rho), ``brake_min`` [m/s^2] (the
    braking the rear vehicle applies at least), ``brake_max`` [m/s^2] (the front vehicle's
    worst braking).
    """
    v_r, v_f = np.asarray(v_rear, dtype=float), np.asarray(v_front, dtype=float)
    reach = v_r + response_time * accel_max
    d = (v_r * response_time + 0.5 * accel_max * response_time**2
         + reach**2 / (2.0 * brake_min) - v_f**2 / (2.0 * brake_max))  # fmt: skip
    return np.maximum(d, 0.0)


def safe_behind(params: ShieldParams, gap: float, v_rear: float, v_front: float) -> bool:
    """Whether a bumper gap [m] is at least the RSS safe distance of ``params``."""
    d = rss_safe_distance(v_rear, v_front, params.response_time, params.accel_max,
                          params.brake_min, params.brake_max)  # fmt: skip
    return gap >= float(d)


@dataclass(frozen=True, slots=True)
class Override:
    """One shield intervention: time [s], vehicle, the vehicle it was unsafe to, and what
    the shield did ("brake", "hold_change" or "release")."""

    t: float
    vehicle: int
    other: int
    action: str


def lane_leaders(c: ListenedRun, i: int) -> list[int]:
    """The nearest active vehicle ahead of ``i`` in each lane its body occupies (its lane,
    and during a change its origin and target lanes)."""
    lanes = {int(c.lane[i]), int(c.origin[i]), int(c.target[i])}
    return [j for j in (lane_neighbours(c, i, lane)[0] for lane in lanes) if j >= 0]


def lane_neighbours(c: ListenedRun, i: int, lane: int) -> tuple[int, int]:
    """``(leader, follower)`` of position ``x[i]`` in ``lane`` (-1: none), ``i`` excluded."""
    active = np.flatnonzero(c.active)
    occupies = (c.origin[active] == lane) | (c.target[active] == lane) | (c.lane[active] == lane)
    there = active[occupies & (active != i)]
    ahead, behind = there[c.x[there] > c.x[i]], there[c.x[there] <= c.x[i]]
    leader = int(ahead[np.argmin(c.x[ahead])]) if ahead.size else -1
    follower = int(behind[np.argmax(c.x[behind])]) if behind.size else -1
    return leader, follower


class Shield:
    """The shield of one run (:class:`~hcomc.config.impairment_tables.ShieldParams`); with
    ``enabled`` false the engines do not call it."""

    def __init__(self, params: ShieldParams, config: ScenarioConfig, fault: DrivenVehicles) -> None:
        self.params, self.config, self.fault = params, config, fault
        self.overrides: list[Override] = []
        self._braking: set[int] = set()  # vehicles the shield drives this step

    def act(self, sim: ListenedRun, t: float, commanded: IntArray) -> None:
        """Check the ``commanded`` vehicles before the next step (see the module docstring)."""
        if not self.params.enabled:
            return
        self._gate_changes(sim, t)
        self.brake(sim, t, commanded)

    def brake(self, sim: ListenedRun, t: float, commanded: IntArray) -> None:
        """Brake each of the ``commanded`` vehicles closer than the RSS distance to the
        nearest vehicle ahead in a lane it occupies; hand back those that no longer are."""
        braking: dict[int, float] = {}
        for i in commanded.tolist():
            if self.fault.drives(i):
                continue
            unsafe = [j for j in lane_leaders(sim, i) if not self._safe(sim, i, j)]
            if unsafe:
                follow = sim.follow(np.full(len(unsafe), i), np.array(unsafe))
                braking[i] = min(float(follow.min()), -self.params.brake_min)
                self.overrides.append(Override(t, i, unsafe[0], "brake"))
        for i in self._braking - braking.keys():
            sim.command(i, math.nan)
        for i, acc in braking.items():
            sim.command(i, acc)
        self._braking = set(braking)

    def unsafe_merge(self, sim: ListenedRun, vr: int) -> list[int]:
        """The vehicles of the lane VR merges into (lane 1 of its ramp) next to which its merge
        would start closer than the RSS distance: its leader there (VR behind it) and its
        follower there (VR ahead)."""
        target = ramp_in(sim.ramps, int(sim.lane[vr])).target
        leader, follower = lane_neighbours(sim, vr, target)
        pairs = ((leader, leader < 0 or self._safe(sim, vr, leader)),
                 (follower, follower < 0 or self._safe(sim, follower, vr)))  # fmt: skip
        return [j for j, ok in pairs if not ok]

    def cannot_stop(self, sim: ListenedRun, vr: int) -> bool:
        """Whether VR could no longer stop before its acceleration lane's end at the safe
        deceleration."""
        stop = stopping_distance(
            float(sim.v[vr]), self.config.lane_change.safe_decel, float(sim.fleet.s0[vr])
        )
        end = ramp_in(sim.ramps, int(sim.lane[vr])).accel_lane_end
        return bool(sim.x[vr] >= end - stop)

    def _safe(self, sim: ListenedRun, rear: int, front: int) -> bool:
        gap = float(sim.x[front] - sim.fleet.length[front] - sim.x[rear])
        return safe_behind(self.params, gap, float(sim.v[rear]), float(sim.v[front]))

    def _gate_changes(self, sim: ListenedRun, t: float) -> None:
        """Hold a commanded merge about to start next to an unsafe gap; release VR to gap
        acceptance once it could no longer stop before the lane end."""
        for vr in sim.merges_due().tolist():
            bad = self.unsafe_merge(sim, vr)
            if not bad:
                continue
            if self.cannot_stop(sim, vr):
                sim.release_merge(vr)
                self.overrides.append(Override(t, vr, bad[0], "release"))
            else:
                sim.hold_merge(vr)
                self.overrides.append(Override(t, vr, bad[0], "hold_change"))

    def counts(self) -> dict[str, int]:
        """Overrides by action."""
        actions = [o.action for o in self.overrides]
        return {a: actions.count(a) for a in ("brake", "hold_change", "release")}
