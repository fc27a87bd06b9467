"""A constant-time-gap (CTG) merge controller: a small, complete merge controller.

Rule. When the ramp vehicle VR and the lane-1 vehicle behind its projection, VMC, are both
CAVs, VR merges ahead of VMC, and VMC opens a gap of ``time_gap * v`` behind VR by the time
VR starts its lane change:

1. VR starts its change at ``merge_x``, 10 m into the acceleration lane (earlier if the
   change would not end on the lane), and gets there after H seconds at its current speed.
2. VMC follows a virtual vehicle VV1, a cubic in τ = t - t0 (paper Eq. 8-10). VV1 starts
   where VMC's own car following is at rest (its equilibrium gap ``s0 + T v`` ahead of VMC,
   at VMC's speed), so VMC feels no jump, and ends at τ = H at VR's projected position,
   moved back by the part of the time gap VMC's headway T does not keep already,
   ``(time_gap - T) v``. VMC keeps ``s0 + T v`` behind VV1, so at the merge it is
   ``time_gap * v`` (plus s0) behind VR.
3. After H the engine replaces VV1 by VR's projection. By default the engine plans once, as
   the paper does; with ``control.replan_period`` > 0 (e.g. ``--set
   control.replan_period=1``) it replans every that many seconds until VR starts its change,
   with the key vehicles identified anew: the constant-speed prediction is corrected as the
   merge draws near, and a VMC that has overtaken VR is VMF from then on (VR merges behind
   it).

Otherwise nobody cooperates (``Mode.NONE``): an HDV VR merges by gap acceptance; a CAV VR
starts its change at ``merge_x`` when that is safe (the engine's MOBIL check), and falls
back to gap acceptance if it never is, when VMC is missing or an HDV, when VMC would stay
far enough behind even at its desired speed, or when VV1 would need a negative speed or
braking beyond ``control.virtual_max_decel``.
"""

from __future__ import annotations

import time

import numpy as np

from hcomc import ConfigError, MergeGroup, MergePlan, Mode, ScenarioConfig, TrafficView
from hcomc.control.longitudinal_candidate import reach_horizon
from hcomc.equations.virtual_vehicle import cubic_coefficients, cubic_extremes
from hcomc.interface import elapsed_ms

MERGE_OFFSET = 10.0
"""VR starts its lane change this far downstream of the acceleration-lane start [m]."""


class ConstantTimeGap:
    """VMC opens a constant time gap for VR (the rule is in the module docstring).

    Parameters
    ----------
    config : the scenario (hcomc passes it).
    time_gap : the gap VMC opens behind VR by the merge, in seconds at VR's speed [s]
        (below VMC's own time headway it changes nothing: VMC never follows closer).
    lane_change_duration : VR's lane-change duration [s]; None: the config's CAV value.
    """

    name = "CTG"

    def __init__(
        self,
        config: ScenarioConfig,
        time_gap: float = 1.5,
        lane_change_duration: float | None = None,
    ) -> None:
        if not time_gap > 0:
            raise ConfigError(f"key 'control.options.time_gap' = {time_gap}; allowed: > 0 s")
        self.time_gap = time_gap
        if lane_change_duration is None:
            lane_change_duration = config.cav.lane_change_duration
        self.duration = lane_change_duration

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        """VMC follows VV1 and opens the gap; VR merges ahead of it at ``merge_x``."""
        start = time.perf_counter()
        vr, vmc = group.vr, group.vmc
        if not view.is_cav(vr):  # an HDV is never commanded
            return MergePlan(group, Mode.NONE, view.t, reason="CTG: HDV VR, gap acceptance")
        ramp, fleet = view.ramp, view.fleet  # the ramp VR is on, on any road
        x_r, v_r = float(view.x[vr]), float(view.v[vr])

        # 1. Merge position: the change (length v * duration) must end on the acceleration lane.
        change_length = max(v_r * self.duration, 3.0 * float(fleet.length[vr]))
        last = ramp.accel_lane_end - change_length
        merge_x = max(min(ramp.accel_lane_start + MERGE_OFFSET, last), ramp.accel_lane_start)
        horizon = reach_horizon(view, vr, merge_x)  # VR's time to merge_x, within [4 s, H_max]

        def alone(why: str) -> MergePlan:  # nobody cooperates; VR changes at merge_x if safe
            return MergePlan(group, Mode.NONE, view.t, merge_x=merge_x,
                             vr_duration=self.duration, reason=f"CTG: {why}",
                             decision_ms=elapsed_ms(start))  # fmt: skip

        if not view.is_cav(vmc):
            return alone("no CAV VMC to open the gap")

        # 2. VR's projection at the merge, and where VMC must be then at the latest.
        x_c, v_c = float(view.x[vmc]), float(view.v[vmc])
        headway, s0, length = float(fleet.T[vmc]), float(fleet.s0[vmc]), float(fleet.length[vr])
        x_merge = x_r + v_r * horizon
        v_free = max(v_c, float(fleet.v0[vmc]))  # VMC left alone drives at its desired speed
        if x_c + v_free * horizon <= x_merge - length - s0 - self.time_gap * v_r:
            return alone("VMC stays far enough behind by itself")

        # 3. VV1: from VMC's equilibrium leader to VR's projection, less the extra time gap.
        x_start = x_c + length + s0 + headway * v_c
        x_end = x_merge - max(self.time_gap - headway, 0.0) * v_r
        vv1 = cubic_coefficients(horizon, x_start, v_c, x_end, v_r)
        v_min, a_min = cubic_extremes(vv1, horizon)
        if v_min < 0.0 or a_min < -view.config.control.virtual_max_decel:
            return alone("VV1 would need v < 0 or too hard braking")
        return MergePlan(
            group,
            Mode.LONGITUDINAL,
            view.t,
            merge_x=merge_x,
            vr_duration=self.duration,
            horizon=horizon,
            vv1=vv1,
            reason=f"CTG: VMC opens {self.time_gap:g} s behind VR, merge at {merge_x:.0f} m",
            decision_ms=elapsed_ms(start),
        )
