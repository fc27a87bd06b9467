"""Traffic demand: arrival schedules per lane and vehicle kinds.

Mainline headways are shifted exponential, ``h = h_min + Exp(mean - h_min)``, so their mean is
the condition's average time headway (paper Table I). The mainline is pre-filled at
``t = -warmup`` with vehicles spaced by headway x speed, and vehicles keep arriving at x = 0
until the end of the run, so traffic is developed when logging starts at t = 0. Each vehicle
is a CAV with probability ``cav_penetration``.

**Random streams.** The demand takes one draw from the run's generator (two 64-bit words,
whatever the duration), the entropy of a :class:`numpy.random.SeedSequence` whose children
``(source, part)`` are the demand's independent streams: source 0 = lane 1, 1 = lane 2,
2 = ramp; part 0 = initial-fill headways, 1 = initial-fill kinds, 2 = arrival headways,
3 = arrival kinds (the ramp has no fill). Headways are drawn in fixed chunks until the span
is covered and each vehicle's kind is the next uniform of its stream's kind generator, in
order of arrival (the fill downstream first), so a run of the same seed with a shorter
duration has exactly the first vehicles of a longer one (same times, positions, speeds,
kinds) and the longer one only adds vehicles released after the shorter duration. Taking a
fixed amount from the run's generator (rather than spawning from it) leaves what the engine
draws next (estimation errors, controllers) independent of the demand drawn.

**Insertion speed.** With ``main_speed = "equilibrium"`` each mainline lane's vehicles enter
at the lane's steady-state speed ``v*``: the speed at which the mean front-to-front spacing
the traffic needs in steady state equals the spacing the lane's demand gives, ``h v``
(mean headway h, every vehicle at the same speed). The needed spacing mixes the kinds by
their share p = ``cav_penetration``:

    p (s_CAV(v) + L) + (1 - p) (s_HDV(v) + L) = h v,

with ``s_K(v)`` the IDM equilibrium gap of kind K (Eq. 1 with v' = 0, Δv = 0:
``(s0 + v T) / sqrt(1 - (v/v0)^δ)``; ``s0 + v T`` for the IIDM), i.e. each vehicle keeps
its own steady-state gap behind a leader at the common speed. Of the two roots the
free-flow one (the larger, just below v0) is used; for the IIDM, whose free-flow steady
state is v0 itself, v0. A headway below the lane's capacity headway (demand above capacity,
e.g. under about 2 s for HDVs with T = 1.5 s) has no free-flow state: vehicles then enter at
the capacity speed and the entry meters them. Inserted at v*, undisturbed traffic neither
accelerates nor brakes on average. A number sets a fixed insertion speed instead.

**Paper scenario** (``pattern = "uniform"``): every headway equals the mean exactly and
the kinds follow an evenly spread pattern with the exact share: the k-th vehicle of a lane
(k = 0, 1, ... in order of travel, downstream first) is a CAV iff
``floor((k + 1) p + 1/2) - floor(k p + 1/2) = 1``, so a lone ramp vehicle takes the more
likely kind. No random number is drawn for the demand (the run's generator is untouched).
``hcomc reproduce`` runs this scenario with ``hdv.estimation_errors = false`` (reaction
delays stay), so the traffic is fully deterministic; only the HCOMC optimisers draw from the
run's seed.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import ConfigError, DemandParams, IDMParams, ScenarioConfig
from hcomc.equations.idm import equilibrium_gap
from hcomc.road import Kind, Lane


@dataclass(frozen=True, slots=True)
class Demand:
    """Every vehicle of a run, sorted by release time (struct of arrays, shape (N,)).

    Attributes
    ----------
    t : release time [s]; vehicles of the initial fill have ``t = -warmup``.
    x : release position of the front bumper [m].
    v : release speed [m/s].
    lane : release lane (its code in the road's lane table, :mod:`hcomc.sim.lane_table`;
        on the paper's road a :class:`~hcomc.road.Lane`).
    kind : :class:`~hcomc.road.Kind` per vehicle.
    scripted : True for a platoon leader that follows the configured speed profile.
    route : the code of the off-ramp lane the vehicle leaves the road by; -1: the
        mainline's end (every vehicle of the paper's road).
    """

    t: FloatArray
    x: FloatArray
    v: FloatArray
    lane: IntArray
    kind: IntArray
    scripted: BoolArray
    route: IntArray

    @property
    def n(self) -> int:
        """Number of vehicles."""
        return int(self.t.size)


HEADWAY_CHUNK = 256
"""Headways drawn per call while the arrivals do not cover the span yet (fixed, so a stream's
draws do not depend on the span and a shorter span's arrivals are a prefix of a longer's)."""


def shifted_exponential(
    rng: np.random.Generator, mean: float, minimum: float, total: float
) -> FloatArray:
    """Cumulative arrival offsets in ``[0, total)`` from shifted exponential headways [s].

    Headways are drawn in chunks of :data:`HEADWAY_CHUNK` until an offset reaches ``total``
    and summed one after another, so the offsets are the same sequence for every ``total``:
    the result for a shorter span is a prefix of the result for a longer one (same stream).
    """
    chunks: list[FloatArray] = []
    last = 0.0
    while last < total:
        headways = minimum + rng.exponential(mean - minimum, size=HEADWAY_CHUNK)
        # a running sum continued from the last offset: bit-identical to one cumsum of all
        offsets = np.cumsum(np.concatenate(([last], headways)))[1:]
        chunks.append(offsets)
        last = float(offsets[-1])
    if not chunks:
        return np.empty(0)
    offsets = np.concatenate(chunks)
    return offsets[offsets < total]


def lane_speed(config: ScenarioConfig, mean_headway: float) -> float:
    """Insertion speed of a mainline lane with the given mean headway [m/s].

    ``demand.main_speed`` if it is a number, else the free-flow steady-state speed ``v*``
    of the module docstring. A headway shorter than the lane's capacity headway has no
    free-flow steady state (the demand exceeds capacity): then the capacity speed ``v_c``,
    at which the steady-state time headway ``spacing(v) / v`` is shortest, is used and the
    entry meters the vehicles (an arrival waits until its gap allows it in).
    """
    d = config.demand
    if not isinstance(d.main_speed, str):
        return float(d.main_speed)
    return _free_flow_speed(d, config.cav, config.hdv, config.road.vehicle_length, mean_headway)


@functools.lru_cache(maxsize=256)  # the same scenario's runs share it (environments, sweeps)
def _free_flow_speed(
    d: DemandParams, cav: IDMParams, hdv: IDMParams, length: float, mean_headway: float
) -> float:
    """The steady-state speed of :func:`lane_speed` (its parameters are immutable)."""
    p = d.cav_penetration
    kinds = [(w, params) for w, params in ((p, cav), (1.0 - p, hdv)) if w > 0]
    v_max = min(params.desired_speed for _, params in kinds)

    def needed(v: Any) -> Any:  # steady-state front-to-front spacing of the mix [m]
        return sum(w * _equilibrium_spacing(v, params, length) for w, params in kinds)

    def excess(v: Any) -> Any:  # needed minus available spacing [m]
        return needed(v) - mean_headway * v

    # scan up to just below v_max (the IDM gap is infinite at v0; the whole grid at once),
    # then refine the last change of sign from "available spacing suffices" to "does not"
    grid = v_max * np.append(np.arange(1, 1000) / 1000.0, 1.0 - 1e-9)
    ok = np.flatnonzero(excess(grid) < 0.0)
    if ok.size == 0:  # over capacity: the speed of the shortest steady-state headway
        k = int(np.argmin(needed(grid) / grid))
        lo, hi = float(grid[max(k - 1, 0)]), float(grid[min(k + 1, grid.size - 1)])
        best = minimize_scalar(lambda v: needed(v) / v, bounds=(lo, hi), method="bounded")
        return float(best.x)
    k = int(ok[-1])
    if k == grid.size - 1:
        return float(v_max)  # IIDM: its free-flow steady state is v0 itself
    return float(brentq(excess, float(grid[k]), float(grid[k + 1]), xtol=1e-10))


def evenly_spread(n: int, share: float) -> np.ndarray:
    """Kinds of n vehicles in order: CAV where ``floor((k+1) p + 1/2) > floor(k p + 1/2)``."""
    k = np.arange(n)
    cav = np.floor((k + 1) * share + 0.5) > np.floor(k * share + 0.5)
    return np.where(cav, Kind.CAV, Kind.HDV)


# the demand's random streams: child (source, part) of the demand's SeedSequence
_LANE_1, _LANE_2, _RAMP = 0, 1, 2  # sources
_FILL, _FILL_KINDS, _ARRIVALS, _ARRIVAL_KINDS = 0, 1, 2, 3  # parts


class _Streams:
    """The demand's independent generators, derived from one draw of the run's generator;
    ``None`` for the uniform pattern, which draws nothing."""

    def __init__(self, rng: np.random.Generator | None) -> None:
        # two 64-bit words, a fixed amount whatever the scenario's duration
        self.entropy = None if rng is None else rng.integers(2**64, size=2, dtype=np.uint64)

    def __call__(self, source: int, part: int) -> np.random.Generator | None:
        if self.entropy is None:
            return None
        seq = np.random.SeedSequence([int(w) for w in self.entropy], spawn_key=(source, part))
        return np.random.default_rng(seq)


def _offsets(
    config: ScenarioConfig, rng: np.random.Generator | None, mean: float, total: float
) -> FloatArray:
    """Arrival offsets in ``[0, total)``: random (shifted exponential) or uniform."""
    d = config.demand
    if d.pattern == "uniform":
        return mean * np.arange(1, int(np.floor(total / mean - 1e-9)) + 1, dtype=np.float64)
    assert rng is not None
    return shifted_exponential(rng, mean, d.min_headway, total)


def _kinds(config: ScenarioConfig, rng: np.random.Generator | None, n: int) -> IntArray:
    """Kinds of n vehicles of one stream in order (random pattern); placeholders (uniform:
    the kinds are spread per lane afterwards)."""
    if rng is None:
        return np.full(n, Kind.HDV, dtype=np.int64)
    draw = rng.random(n)  # one uniform per vehicle, in order: a prefix for fewer vehicles
    return np.where(draw < config.demand.cav_penetration, Kind.CAV, Kind.HDV).astype(np.int64)


def _merge_demand(config: ScenarioConfig, rng: np.random.Generator) -> Demand:
    d, road = config.demand, config.road
    start, end = -config.warmup, config.duration
    stream = _Streams(rng if d.pattern == "random" else None)
    t_parts, x_parts, v_parts, lane_parts, kind_parts = [], [], [], [], []

    def add(t: FloatArray, x: FloatArray, v: float, lane: int, kind: IntArray) -> None:
        t_parts.append(t)
        x_parts.append(x)
        v_parts.append(np.full(t.size, v))
        lane_parts.append(np.full(t.size, lane))
        kind_parts.append(kind)

    mains = ((_LANE_1, Lane.MAIN_1, d.mean_headway_main_1),
             (_LANE_2, Lane.MAIN_2, d.mean_headway_main_2))  # fmt: skip
    for source, lane, mean in mains:
        speed = lane_speed(config, mean)
        # initial fill: spacings headway * speed upstream from the road's end, downstream first
        offsets = _offsets(config, stream(source, _FILL), mean, road.length / speed)
        fill = road.length - offsets * speed
        kinds = _kinds(config, stream(source, _FILL_KINDS), fill.size)
        on_road = fill > 0
        add(np.full(int(on_road.sum()), start), fill[on_road], speed, lane, kinds[on_road])
        arrivals = start + _offsets(config, stream(source, _ARRIVALS), mean, end - start)
        kinds = _kinds(config, stream(source, _ARRIVAL_KINDS), arrivals.size)
        add(arrivals, np.zeros(arrivals.size), speed, lane, kinds)
    if d.ramp == "single":
        ramp_t = np.array([d.ramp_entry_time]) if d.ramp_entry_time < end else np.empty(0)
    elif d.ramp == "flow":
        mean = d.ramp_mean_headway
        ramp_t = start + _offsets(config, stream(_RAMP, _ARRIVALS), mean, end - start)
    else:
        ramp_t = np.empty(0)
    kinds = _kinds(config, stream(_RAMP, _ARRIVAL_KINDS), ramp_t.size)
    add(ramp_t, np.full(ramp_t.size, road.ramp_start), d.ramp_speed, Lane.RAMP, kinds)
    t = np.concatenate(t_parts)
    x = np.concatenate(x_parts).astype(np.float64)
    lanes = np.concatenate(lane_parts).astype(np.int64)
    kind = np.concatenate(kind_parts).astype(np.int64)
    if d.pattern == "uniform":
        for lane in np.unique(lanes):
            ids = np.flatnonzero(lanes == lane)
            travel = ids[np.lexsort((-x[ids], t[ids]))]  # order of travel, downstream first
            kind[travel] = evenly_spread(ids.size, d.cav_penetration)
    order = np.lexsort((-x, t))  # by time, downstream first
    return Demand(
        t=t[order],
        x=x[order],
        v=np.concatenate(v_parts)[order],
        lane=lanes[order],
        kind=kind[order],
        scripted=np.zeros(t.size, dtype=bool),
        route=np.full(t.size, -1, dtype=np.int64),
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
        x=x.astype(np.float64, copy=False),
        v=np.full(n, p.initial_speed),
        lane=np.full(n, Lane.MAIN_1, dtype=np.int64),
        kind=kind,
        scripted=scripted,
        route=np.full(n, -1, dtype=np.int64),
    )


def _equilibrium_spacing(v: Any, params: IDMParams, length: float) -> Any:
    """Front-to-front spacing of the IDM/IIDM steady state at speed(s) v [m] (a float for a
    float, an array for an array)."""
    if params.variant == "iidm":
        return params.min_gap + v * params.time_headway + length
    gap = equilibrium_gap(
        v, v0=params.desired_speed, T=params.time_headway, s0=params.min_gap,
        delta=params.exponent,
    )  # fmt: skip
    return (float(gap) if np.ndim(v) == 0 else gap) + length


def generate_demand(config: ScenarioConfig, rng: np.random.Generator) -> Demand:
    """Every vehicle of the run (merge scenario or scripted-leader platoon)."""
    if config.scenario == "platoon":
        return _platoon_demand(config)
    return _merge_demand(config, rng)
