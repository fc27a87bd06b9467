"""Traffic demand: arrival schedules per lane and vehicle kinds (DESIGN.md §3).

Mainline headways are shifted exponential, ``h = h_min + Exp(mean - h_min)``, so their mean is
the condition's average time headway (paper Table I). The mainline is pre-filled at
``t = -warmup`` with vehicles spaced by headway x speed, and vehicles keep arriving at x = 0
until the end of the run, so traffic is developed when logging starts at t = 0. Each vehicle
is a CAV with probability ``cav_penetration``. All draws come from the run's one generator,
in a fixed order (lane 1, lane 2, ramp, kinds), so the same seed gives the same demand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import ConfigError, IDMParams, ScenarioConfig
from hcomc.models.idm import equilibrium_gap
from hcomc.road import Kind, Lane


@dataclass(frozen=True, slots=True)
class Demand:
    """Every vehicle of a run, sorted by release time (struct of arrays, shape (N,)).

    Attributes
    ----------
    t : release time [s]; vehicles of the initial fill have ``t = -warmup``.
    x : release position of the front bumper [m].
    v : release speed [m/s].
    lane : release lane (:class:`~hcomc.road.Lane`).
    kind : :class:`~hcomc.road.Kind` per vehicle.
    scripted : True for a platoon leader that follows the configured speed profile.
    """

    t: FloatArray
    x: FloatArray
    v: FloatArray
    lane: IntArray
    kind: IntArray
    scripted: BoolArray

    @property
    def n(self) -> int:
        """Number of vehicles."""
        return int(self.t.size)


def shifted_exponential(
    rng: np.random.Generator, mean: float, minimum: float, total: float
) -> FloatArray:
    """Cumulative arrival offsets in ``[0, total)`` from shifted exponential headways [s]."""
    n = int(total / mean * 1.5) + 16
    while True:
        offsets = np.cumsum(minimum + rng.exponential(mean - minimum, size=n))
        if offsets[-1] >= total:
            return offsets[offsets < total]
        n *= 2  # pragma: no cover - astronomically rare with the 1.5 safety factor


def _merge_demand(config: ScenarioConfig, rng: np.random.Generator) -> Demand:
    d, road = config.demand, config.road
    start, end = -config.warmup, config.duration
    t_parts, x_parts, v_parts, lane_parts = [], [], [], []
    for lane, mean in ((Lane.MAIN_1, d.mean_headway_main_1), (Lane.MAIN_2, d.mean_headway_main_2)):
        # initial fill: spacings headway * speed downstream from x = 0
        fill = (
            road.length
            - shifted_exponential(rng, mean, d.min_headway, road.length / d.main_speed)[::-1]
            * d.main_speed
        )
        fill = fill[fill > 0]
        arrivals = start + shifted_exponential(rng, mean, d.min_headway, end - start)
        t_parts += [np.full(fill.size, start), arrivals]
        x_parts += [fill, np.zeros(arrivals.size)]
        v_parts += [np.full(fill.size + arrivals.size, d.main_speed)]
        lane_parts += [np.full(fill.size + arrivals.size, lane)]
    if d.ramp == "single":
        ramp_t = np.array([d.ramp_entry_time]) if d.ramp_entry_time < end else np.empty(0)
    elif d.ramp == "flow":
        ramp_t = start + shifted_exponential(rng, d.ramp_mean_headway, d.min_headway, end - start)
    else:
        ramp_t = np.empty(0)
    t_parts.append(ramp_t)
    x_parts.append(np.full(ramp_t.size, road.ramp_start))
    v_parts.append(np.full(ramp_t.size, d.ramp_speed))
    lane_parts.append(np.full(ramp_t.size, Lane.RAMP))
    t = np.concatenate(t_parts)
    kind = np.where(rng.random(t.size) < d.cav_penetration, Kind.CAV, Kind.HDV)
    order = np.lexsort((-np.concatenate(x_parts), t))  # by time, downstream first
    return Demand(
        t=t[order],
        x=np.concatenate(x_parts)[order],
        v=np.concatenate(v_parts)[order],
        lane=np.concatenate(lane_parts).astype(np.int64)[order],
        kind=kind.astype(np.int64)[order],
        scripted=np.zeros(t.size, dtype=bool),
    )


def _platoon_demand(config: ScenarioConfig) -> Demand:
    """Leader at 3/4 of the road, K followers behind it at their equilibrium spacing."""
    p, road = config.platoon, config.road
    params = config.hdv if p.kind == "hdv" else config.cav
    n = p.followers + 1
    spacing = _equilibrium_spacing(p.initial_speed, params, road.vehicle_length)
    x = 0.75 * road.length - spacing * np.arange(n)
    if x[-1] < 0:
        fits = int(0.75 * road.length // spacing)
        raise ConfigError(
            f"key 'platoon.followers' = {p.followers}: {n} vehicles at their equilibrium "
            f"spacing {spacing:.1f} m do not fit on road.length = {road.length} m; allowed: "
            f"platoon.followers <= {fits}, or road.length >= {4 / 3 * spacing * n:.0f}"
        )
    kind = np.full(n, Kind.HDV if p.kind == "hdv" else Kind.CAV, dtype=np.int64)
    kind[0] = Kind.CAV  # the scripted leader has exact perception; its model is not used
    scripted = np.zeros(n, dtype=bool)
    scripted[0] = True
    return Demand(
        t=np.full(n, -config.warmup),
        x=x,
        v=np.full(n, p.initial_speed),
        lane=np.full(n, Lane.MAIN_1, dtype=np.int64),
        kind=kind,
        scripted=scripted,
    )


def _equilibrium_spacing(v: float, params: IDMParams, length: float) -> float:
    """Front-to-front spacing of the IDM/IIDM steady state at speed v [m]."""
    if params.variant == "iidm":
        gap = params.min_gap + v * params.time_headway
    else:
        gap = float(
            equilibrium_gap(
                v,
                v0=params.desired_speed,
                T=params.time_headway,
                s0=params.min_gap,
                delta=params.exponent,
            )
        )
    return gap + length


def generate_demand(config: ScenarioConfig, rng: np.random.Generator) -> Demand:
    """Every vehicle of the run (merge scenario or scripted-leader platoon)."""
    if config.scenario == "platoon":
        return _platoon_demand(config)
    return _merge_demand(config, rng)
