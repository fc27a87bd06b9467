"""Where the step's time goes: each phase of the compiled step timed inside the compiled loop,
beside a plain-IDM loop on the same machine as the physical reference.

The phases are those of :func:`hcomc.sim.step.loop.run_steps`, called in its order by a
compiled driver (:func:`timed_steps`) that reads the processor's cycle counter between them
(``llvm.readcyclecounter``, a few nanoseconds a read, no call into Python), so the split adds
almost nothing to the step it measures:

==============  ===============================================================================
phase           kernels
==============  ===============================================================================
release         :func:`~hcomc.sim.step.loop.begin_step`: event room, Eq. 2 error innovations,
                the vehicles due
decide?         :func:`~hcomc.sim.step.loop.needs_python`: does a controller decide now
                (and :func:`~hcomc.sim.step.loop.count_on_road`)
on road         :func:`~hcomc.sim.step.loop.road_ids`
plans in        the live plans' followers and virtual leaders (Section III-A)
speed zones     desired speeds capped by the road's limits (roads that have them)
neighbours      the step's sorted lane entries and every vehicle's leader
follow          Eq. 2 perception of HDVs and Eq. 1/3 car following
blend           Eq. 14 for lane changers
limits          lane ends, virtual leaders, commands, the emergency limit
plans out       the plans' commanded changes and their end
lane changes    discretionary and mandatory decisions (MOBIL, gap acceptance)
collisions      Eq. 7 between the entries of each lane
integrate       the ballistic update
lateral         Eq. 4-6 quintic lateral motion
bookkeeping     exits, missed exits, waits at a lane's end
errors          the HDVs' error processes (Eq. 2)
history         the perception ring buffer
log             the log row (every ``log_interval``)
==============  ===============================================================================

Cycles are turned into seconds with the wall time of the whole timed stretch. The driver
must step exactly as the engine does: before timing, the scene is run once by the engine and
once by the driver, and the benchmark stops unless both end in the same state to the bit.

The reference is a plain IDM on one lane (each vehicle behind the one ahead, no perception,
no log; ``plain_idm``), the 56-59 M vehicle-steps/s a compiled loop reaches on these hosts.
Beside it, on the line, the paper's car following alone (``paper_following``): the line's
vehicles with Eq. 2's two error draws a driver, its delayed, noisy perception and Eq. 1/3
by the engine's own equation kernels, the ballistic update and the delays' ring buffer, and
nothing else: what a step of these equations costs by itself, before the rest of the step.

Run: ``python benchmarks/step_cost.py [--sizes 100 2000] [--duration 60] [--json]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

sys.path.insert(0, str(Path(__file__).resolve().parent))

from vs_sumo import SEED, line_config, scene_config

from hcomc.config import load_config
from hcomc.equations.car_following import follow_accel
from hcomc.equations.integrate import ballistic_step
from hcomc.equations.perception import ErrorScales, interpolate, perceived
from hcomc.sim.engine import Simulation
from hcomc.sim.lane_table import L_END, L_KIND, L_OPENS, L_SPEED
from hcomc.sim.neighbours import lookup_one, neighbours_into
from hcomc.sim.perception import advance_errors_of, perception_rows
from hcomc.sim.step import loop
from hcomc.sim.step import state as S  # noqa: N812
from hcomc.sim.step.collisions import check_collisions
from hcomc.sim.step.lane_change import discretionary_changes, start_lane_changes
from hcomc.sim.step.motion import (
    _blend_changers,
    _limits,
    bookkeeping,
    follow_into,
    integrate,
    lane_index,
    lateral,
)
from hcomc.sim.step.plans import (
    execute_plans,
    finish_plans,
    following_into,
    virtual_rows_into,
)
from hcomc.sim.step.road import section_at, speed_limit

PHASES = (
    "release", "decide?", "on road", "plans in", "speed zones", "neighbours", "follow", "blend",
    "limits", "plans out", "lane changes", "collisions", "integrate", "lateral", "bookkeeping",
    "errors", "history", "log",
)  # fmt: skip
N_PHASES = len(PHASES)


@intrinsic
def cycles(typingctx):  # type: ignore[no-untyped-def]
    """The processor's cycle counter (``llvm.readcyclecounter``)."""

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        fnty = ir.FunctionType(ir.IntType(64), [])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.readcyclecounter")
        return builder.call(fn, [])

    return types.int64(), codegen


@njit
def _front(c, ids, t, spent):  # type: ignore[no-untyped-def]
    """:func:`~hcomc.sim.step.loop.step_front` phase by phase."""
    t0 = cycles()
    n_plans = c.counters[S.N_PLANS]
    following = following_into(c.plan_int, n_plans, c.scratch_b[S.S_FOLLOWING, : c.x.size])
    fol, rows = c.scratch_int[S.S_VV_FOL], c.scratch_f[S.S_VV : S.S_VV + 4]
    m = virtual_rows_into(c.plan_int, c.plan_f, n_plans, t, c.x, c.v, c.a, c.length, fol, rows)
    t1 = cycles()
    spent[3] += t1 - t0
    n = ids.size
    if c.flags[S.SPEED_LIMITS] > 0:
        kinds, rows, sec_x0, sec_speed = c.road_int[L_KIND], c.road_f, c.sec_x0, c.sec_speed
        matrix, desired, lane, x = c.matrix, c.desired, c.lane, c.x
        for k in range(n):
            i, g = ids[k], lane[ids[k]]
            limit = speed_limit(kinds[g], rows[L_OPENS, g], rows[L_END, g], rows[L_SPEED, g],
                                sec_speed[section_at(sec_x0, x[i])], x[i])  # fmt: skip
            matrix[0, i] = min(desired[i], limit)
    t2 = cycles()
    spent[4] += t2 - t1
    changing = c.scratch_b[S.S_CHANGING, :n]
    for k in range(n):
        changing[k] = c.origin[ids[k]] != c.target[ids[k]]
    index, in_ori, in_tgt = lane_index(c, ids, changing)
    vs, ls, ks, rank = index
    lead = c.scratch_int[S.S_LEAD, :n]
    neighbours_into(vs, ls, rank, 1, lead)
    for k in range(n):
        if changing[k]:
            i = ids[k]
            lead[k] = lookup_one(ks, ls, vs, c.origin[i], c.x[i])[0]
    t3 = cycles()
    spent[5] += t3 - t2
    acc = c.scratch_f[S.S_ACC, :n]
    follow_into(c, ids, lead, acc)
    t4 = cycles()
    spent[6] += t4 - t3
    _blend_changers(c, ids, t, acc, changing, in_ori, in_tgt, index)
    t5 = cycles()
    spent[7] += t5 - t4
    _limits(c, ids, t, acc, changing, following, fol[:m], rows[0, :m], rows[1, :m],
            rows[2, :m], rows[3, :m])  # fmt: skip
    t6 = cycles()
    spent[8] += t6 - t5
    if n_plans > 0:
        execute_plans(c, ids, t, lead, index)
    spent[9] += cycles() - t6
    return acc, changing, index, lead


@njit
def _back(c, ids, t, acc, index, spent):  # type: ignore[no-untyped-def]
    """:func:`~hcomc.sim.step.loop.step_back` phase by phase."""
    t0 = cycles()
    check_collisions(c, t, index)
    t1 = cycles()
    spent[11] += t1 - t0
    integrate(c, ids, acc)
    t2 = cycles()
    spent[12] += t2 - t1
    lateral(c, ids, t)
    t3 = cycles()
    spent[13] += t3 - t2
    bookkeeping(c, ids, t)
    t4 = cycles()
    spent[14] += t4 - t3
    if c.flags[S.ERRORS] > 0:
        xi = c.innov[c.counters[S.INNOV_CURSOR]]
        advance_errors_of(c.w_gap, c.w_ttc, ids, c.is_hdv, xi, c.consts[S.DECAY],
                          c.consts[S.KICK])  # fmt: skip
    t5 = cycles()
    spent[15] += t5 - t4
    loop.end_step(c)
    t6 = cycles()
    spent[16] += t6 - t5
    if c.counters[S.N_PLANS] > 0:
        finish_plans(c)
    spent[9] += cycles() - t6


@njit
def timed_steps(c, stop, log_rows, rng, spent):  # type: ignore[no-untyped-def]
    """:func:`~hcomc.sim.step.loop.run_steps` with the cycles of each phase added to
    ``spent`` (int64, one per :data:`PHASES`)."""
    while c.counters[S.STEP] < stop:
        t0 = cycles()
        if not loop.begin_step(c, rng):
            return S.FLUSH
        t = loop.step_time(c)
        t1 = cycles()
        spent[0] += t1 - t0
        ids = loop.road_ids(c)
        t2 = cycles()
        spent[2] += t2 - t1
        if loop.needs_python(c, t, ids):
            return S.NEED_PYTHON
        loop.count_on_road(c, ids)
        spent[1] += cycles() - t2
        if ids.size > 0:
            acc, changing, index, lead = _front(c, ids, t, spent)
            t3 = cycles()
            if (c.counters[S.STEP] % c.flags[S.DECIDE_EVERY] == 0) and c.flags[S.PLATOON] == 0:
                chosen, target = discretionary_changes(c, ids, changing, loop.holding(c), lead,
                                                       index)  # fmt: skip
                start_lane_changes(c, chosen, target, t, c.consts[:0])
            spent[10] += cycles() - t3
            _back(c, ids, t, acc, index, spent)
        t4 = cycles()
        if not loop.record_due_row(c, log_rows):
            spent[17] += cycles() - t4
            return S.GROW_LOG
        spent[17] += cycles() - t4
    return S.DONE


def run_timed(sim: Simulation, spent: np.ndarray) -> None:
    """Run ``sim`` to its end through :func:`timed_steps` (the engine's own Python side at
    its decisions, as :meth:`~hcomc.sim.engine.Simulation.run_to` does)."""
    while not sim.finished:
        sim.resume(timed_steps(sim.core, sim.stop_step, sim.logging, sim.rng, spent))


@njit
def plain_idm(x, v, length, steps, dt, v0, T, a_max, b, s0, delta):  # type: ignore[no-untyped-def]
    """A plain IDM on one lane: vehicle i follows i - 1 (vehicle 0 cruises); ballistic update.
    The physical reference: what a compiled loop does per vehicle-step (``delta`` a number
    known at run time, as the engine's parameters are, not a literal the compiler could
    turn into multiplications)."""
    n = x.size
    acc = np.zeros(n)
    for _ in range(steps):
        acc[0] = 0.0
        for i in range(1, n):
            s = x[i - 1] - length - x[i]
            dv = v[i] - v[i - 1]
            s_star = s0 + max(0.0, v[i] * T + v[i] * dv / (2.0 * np.sqrt(a_max * b)))
            acc[i] = a_max * (1.0 - (v[i] / v0) ** delta - (s_star / max(s, 0.1)) ** 2)
        for i in range(n):
            a = max(acc[i], -9.0)
            dx = v[i] * dt + 0.5 * a * dt * dt
            if v[i] + a * dt < 0.0:
                dx = -0.5 * v[i] * v[i] / a
            x[i] += dx
            v[i] = max(v[i] + a * dt, 0.0)
    return x


def plain_idm_rate(n: int, steps: int, repeats: int) -> float:
    """Vehicle-steps/s of :func:`plain_idm` at ``n`` vehicles (median of ``repeats``)."""
    spacing = 25.0 * 2.0 + 5.0 + 2.0
    rates = []
    plain_idm(np.arange(10.0)[::-1] * spacing, np.full(10, 25.0), 5.0, 2, 0.1, 33.3, 1.6, 1.0,
              1.5, 2.0, 4.0)  # fmt: skip
    for _ in range(repeats):
        x, v = np.arange(float(n))[::-1] * spacing, np.full(n, 25.0)
        start = time.perf_counter()
        plain_idm(x, v, 5.0, steps, 0.1, 33.3, 1.6, 1.0, 1.5, 2.0, 4.0)
        rates.append(n * steps / (time.perf_counter() - start))
    return float(np.median(rates))


@njit
def paper_following(c, steps, rng):  # type: ignore[no-untyped-def]
    """The paper's car following alone on the line scene's vehicles ``c`` (the arrays of
    its run, :class:`~hcomc.sim.step.state.CoreArrays`): each step, the HDVs' two error
    innovations of Eq. 2 drawn per driver, their delayed, noisy perception of the vehicle
    ahead (Eq. 2) and Eq. 1/3, the ballistic update and the ring buffer of the delays,
    with the engine's equation kernels and nothing else (no neighbours, lane changes,
    collisions, log or bookkeeping): what a step of these equations costs by itself with the
    engine's kernels."""
    n, size, dt = c.x.size, c.x_hist.shape[0], c.consts[S.DT]
    x, v, matrix, iidm, length = c.x.copy(), c.v.copy(), c.matrix, c.iidm, c.length
    x_hist, v_hist, w_gap, w_ttc = c.x_hist.copy(), c.v_hist.copy(), c.w_gap.copy(), c.w_ttc.copy()
    decay, kick = c.consts[S.DECAY], c.consts[S.KICK]
    scales = ErrorScales(c.consts[S.GAP_ERROR], c.consts[S.TTC_ERROR], c.flags[S.ERRORS] > 0)
    acc = np.zeros(n)
    for step in range(steps):
        for i in range(n):
            w_gap[i] = decay * w_gap[i] + kick * rng.standard_normal()
            w_ttc[i] = decay * w_ttc[i] + kick * rng.standard_normal()
        (n0, p0, r0), (n1, p1, r1), (n2, p2, r2) = perception_rows(step, c.taus, dt, size)
        for i in range(n):  # vehicle i follows i - 1, as on the line
            has = i > 0
            lead = i - 1 if has else i
            x_i = interpolate(x_hist[n0, i], x_hist[p0, i], r0)
            x_l = interpolate(x_hist[n0, lead], x_hist[p0, lead], r0)
            v_i = interpolate(v_hist[n1, i], v_hist[p1, i], r1)
            dv = interpolate(v_hist[n2, i], v_hist[p2, i], r2) - interpolate(
                v_hist[n2, lead], v_hist[p2, lead], r2
            )
            s_est, v_est, vl_est = perceived(
                x_i, x_l, length[lead], v_i, dv, has, w_gap[i], w_ttc[i], scales
            )
            acc[i] = follow_accel(s_est, v_est, vl_est, 0.0, matrix[0, i], matrix[1, i],
                                  matrix[2, i], matrix[3, i], matrix[4, i], matrix[5, i],
                                  matrix[6, i], iidm[i])  # fmt: skip
        for i in range(n):
            dx, v[i], _ = ballistic_step(v[i], acc[i], dt)
            x[i] += dx
        row = (step + 1) % size
        x_hist[row] = x
        v_hist[row] = v
    return x


def paper_following_rate(config: Any, repeats: int) -> float:
    """Vehicle-steps/s of :func:`paper_following` on the vehicles of ``config``'s run (the
    line scene), the whole run's steps, the best of ``repeats``."""
    sim = Simulation(config, SEED)
    sim.run_to(1)  # released, on the road: the arrays hold the scene's vehicles
    arrays, steps = sim.core._arrays, sim.n_warmup + sim.n_steps
    paper_following(arrays, 2, np.random.default_rng(0))  # compiled before timing
    best = 0.0
    for rep in range(repeats):
        start = time.perf_counter()
        paper_following(arrays, steps, np.random.default_rng(rep))
        best = max(best, arrays.x.size * steps / (time.perf_counter() - start))
    return best


def _same_state(a: Simulation, b: Simulation) -> bool:
    fields = ("x", "v", "a", "y", "lane", "active")
    return all(np.array_equal(getattr(a.arrays, f), getattr(b.arrays, f)) for f in fields)


def _scene(scene: str, n: int, duration: float) -> tuple[Any, Callable[[Any], Simulation]]:
    """The config of ``scene`` and what makes its run: ``line`` and ``onramp`` of
    ``vs_sumo.py`` at about ``n`` vehicles; ``corridor``, the preset's first ``duration``
    seconds without a controller (its own seed, every vehicle logged every step, as
    ``corridor.py`` and ``hcomc simulate corridor`` run it; ``n`` is ignored); ``c1``,
    Condition 1 as configured (the run of ``vs_sumo.py``'s ensemble; ``n`` and ``duration``
    ignored)."""
    if scene == "c1":
        return load_config("C1"), lambda cfg: Simulation(cfg, SEED)
    if scene != "corridor":
        config = line_config(n, duration) if scene == "line" else scene_config(n, duration)
        return config, lambda cfg: Simulation(cfg, SEED)
    from hcomc.corridor import load_corridor
    from hcomc.sim.corridor_scene import corridor_config, corridor_scene

    corridor = load_corridor("corridor", {})
    seed, dt = corridor.corridor.seed, corridor.corridor.step_length
    config = corridor_config(corridor, duration=duration, seed=seed,
                             control={"controller": "none"}, log_interval=dt)  # fmt: skip
    return config, lambda cfg: Simulation(cfg, seed, scene=corridor_scene(corridor))


def measure(scene: str, n: int, duration: float, repeats: int) -> dict[str, object]:
    """The phases of ``scene`` at ``n`` vehicles: ns per vehicle-step each (of the fastest
    timed run), the step's vehicle-steps/s untimed and timed (the best of ``repeats`` each)."""
    config, make = _scene(scene, n, duration)
    plain, split = make(config), make(config)
    plain.run()
    run_timed(split, np.zeros(N_PHASES, dtype=np.int64))
    if not _same_state(plain, split):
        raise SystemExit(f"{scene} {n}: the timed driver does not step as the engine does")
    rate, timed_rate, phases = 0.0, 0.0, {}
    for _ in range(repeats):  # the best untimed run and, apart, the best timed one
        untimed = make(config)
        start = time.perf_counter()
        untimed.run()
        rate = max(rate, untimed.vehicle_steps / (time.perf_counter() - start))
        sim, spent = make(config), np.zeros(N_PHASES, dtype=np.int64)
        start = time.perf_counter()
        run_timed(sim, spent)
        wall = time.perf_counter() - start
        if sim.vehicle_steps / wall > timed_rate:
            timed_rate = sim.vehicle_steps / wall
            ns = wall / max(int(spent.sum()), 1) * 1e9  # per cycle
            phases = {p: float(spent[k] * ns / sim.vehicle_steps) for k, p in enumerate(PHASES)}
    steps = plain.n_warmup + plain.n_steps
    vehicles = n if scene in ("line", "onramp") else round(plain.vehicle_steps / steps)  # on road
    return {"scene": scene, "vehicles": vehicles, "vehicle_steps": plain.vehicle_steps,
            "rate": rate, "timed_rate": timed_rate, "ns_per_vehicle_step": phases}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 2000])
    parser.add_argument("--scenes", nargs="+", default=["line", "onramp"],
                        choices=["line", "onramp", "corridor", "c1"])  # fmt: skip
    parser.add_argument("--duration", type=float, default=60.0)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    sized = [s for s in args.scenes if s in ("line", "onramp")]
    rows = [measure(s, n, args.duration, args.repeats) for n in args.sizes for s in sized]
    for scene in ("c1", "corridor"):
        if scene in args.scenes:
            rows.append(measure(scene, 0, args.duration, args.repeats))
    sizes = {int(row["vehicles"]) for row in rows}  # type: ignore[call-overload]
    idm = {n: plain_idm_rate(n, round(args.duration / 0.1), args.repeats) for n in sorted(sizes)}
    floor = {n: paper_following_rate(line_config(n, args.duration), args.repeats)
             for n in args.sizes if "line" in args.scenes}  # fmt: skip
    if args.json:
        print(json.dumps({"phases": rows, "plain_idm": idm, "paper_following": floor}, indent=1))
        return
    for row in rows:
        n = int(row["vehicles"])  # type: ignore[call-overload]
        parts = row["ns_per_vehicle_step"]
        total = sum(parts.values())  # type: ignore[union-attr]
        print(
            f"{row['scene']} {n}: {row['rate'] / 1e6:.2f} M vehicle-steps/s "
            f"({1e9 / row['rate']:.0f} ns each; timed {total:.0f} ns); plain IDM "
            f"{idm[n] / 1e6:.1f} M ({1e9 / idm[n]:.0f} ns)"
            + (
                f"; the paper's car following alone {1e9 / floor[n]:.0f} ns"
                if row["scene"] == "line" and n in floor
                else ""
            )
        )  # type: ignore[operator]
        for phase, value in sorted(parts.items(), key=lambda kv: -kv[1]):  # type: ignore[union-attr]
            print(f"  {phase:13s} {value:7.1f} ns  {100 * value / total:5.1f} %")


if __name__ == "__main__":
    main()
