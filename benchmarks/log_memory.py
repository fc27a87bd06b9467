"""Memory of a simulation log: a 1-hour run of about 2000 vehicles, per logging interval.

**The run.** Condition C1 for one hour with a continuous demand of about 2000 vehicles
(mean headway ``--headway`` s on each main lane, a ramp flow every 20 s), simulated by the
engine in a fresh child process per logging interval. Measured: the finished log's
``nbytes``, its slot columns (the most vehicles on the road at once), the growth of the
child's resident memory over building and running the simulation (VmRSS; Linux only) and
its peak resident memory (VmHWM).

**The worst case.** ``--vehicles`` vehicles all on the road at once for the whole hour need
a column each: the size of that log from ``SimulationLog.bytes_needed`` (the figure the
``log_memory_limit`` check uses), allocated and filled row by row in a child process
unless ``--no-measure``.

    python benchmarks/log_memory.py [--json] [--intervals 0.1 0.2 0.3 0.5 1.0]
        [--duration 3600] [--headway 4.0] [--vehicles 2000] [--dt 0.1] [--no-measure]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

import numpy as np
from throughput import machine

from hcomc.sim.log import SimulationLog

GIB = 2**30
TARGET_GIB = 0.6  # project target for a 1-hour, 2000-vehicle log


def log_rows(duration: float, dt: float, interval: float) -> int:
    """Rows the engine allocates: every ``interval / dt``-th of ``duration / dt`` steps, + t = 0."""
    every = round(interval / dt)
    if every < 1 or abs(interval / dt - every) > 1e-9:
        raise SystemExit(f"--intervals: {interval} is not a multiple of dt = {dt}")
    return round(duration / dt) // every + 1


def _vm_kib(field: str) -> int | None:
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


def run_child(duration: float, dt: float, interval: float, headway: float) -> dict[str, object]:
    """Simulate the 1-hour run in this process; its log's size and the memory it took."""
    from hcomc.config import load_config
    from hcomc.sim.engine import Simulation

    config = load_config(
        "C1", duration=duration, dt=dt, log_interval=interval,
        demand={"mean_headway_main_1": headway, "mean_headway_main_2": headway, "ramp": "flow"},
    )  # fmt: skip
    rss0 = _vm_kib("VmRSS")
    start = time.perf_counter()
    sim = Simulation(config, 0)
    log = sim.run()
    wall = time.perf_counter() - start
    rss1, peak = _vm_kib("VmRSS"), _vm_kib("VmHWM")
    return {
        "vehicles": log.n_vehicles,
        "rows": log.n_steps,
        "slot_columns": log.n_slots,
        "nbytes": log.nbytes,
        "gib": round(log.nbytes / GIB, 4),
        "dense_bytes": SimulationLog.bytes_needed(log.n_steps, log.n_vehicles),
        "rss_growth_bytes": None if rss0 is None or rss1 is None else (rss1 - rss0) * 1024,
        "peak_rss_bytes": None if peak is None else peak * 1024,
        "vehicle_steps": log.vehicle_steps,
        "run_wall_s": round(wall, 2),
        "meets_target": log.nbytes <= TARGET_GIB * GIB,
    }


def fill_child(rows: int, vehicles: int, interval: float) -> dict[str, object]:
    """Allocate and fill the worst-case log (every vehicle on the road at every row)."""
    rng = np.random.default_rng(0)
    states = rng.uniform(0.0, 1500.0, (5, vehicles))
    lane = rng.integers(0, 3, vehicles)
    rss0 = _vm_kib("VmRSS")
    log = SimulationLog.allocate(
        rows, vehicles, dt=interval, kind=np.ones(vehicles, dtype=np.int8),
        length=np.full(vehicles, 5.0), width=np.full(vehicles, 1.8),
    )  # fmt: skip
    on = np.ones(vehicles, dtype=bool)
    for k in range(rows):
        log.record(k, k * interval, *states, lane=lane, active=on)
    rss1 = _vm_kib("VmRSS")
    grown = None if rss0 is None or rss1 is None else (rss1 - rss0) * 1024
    return {"nbytes": log.nbytes, "rss_growth_bytes": grown}


def _child(*args: object) -> dict[str, object]:
    """Run this script's ``--child`` mode in a fresh interpreter (memory is the child's own)."""
    cmd = [sys.executable, __file__, "--child", *map(str, args)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    result: dict[str, object] = json.loads(out)
    return result


def _num(value: object) -> str:
    return f"{value:,}" if isinstance(value, int) else "-"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--intervals", type=float, nargs="+", default=[0.1, 0.2, 0.3, 0.5, 1.0])
    parser.add_argument("--duration", type=float, default=3600.0, help="measured seconds")
    parser.add_argument("--headway", type=float, default=4.0, help="main-lane headway [s]")
    parser.add_argument("--vehicles", type=int, default=2000, help="worst case: N on the road")
    parser.add_argument("--dt", type=float, default=0.1, help="simulation step [s]")
    parser.add_argument("--no-measure", action="store_true", help="worst case: sizes only")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        kind, *rest = args.child
        if kind == "run":
            duration, dt, interval, headway = map(float, rest)
            print(json.dumps(run_child(duration, dt, interval, headway)))
        else:
            print(json.dumps(fill_child(int(rest[0]), int(rest[1]), float(rest[2]))))
        return

    runs, worst = [], []
    for interval in args.intervals:
        rows = log_rows(args.duration, args.dt, interval)  # also checks the interval
        run = {"log_interval_s": interval, "every_kth_step": round(interval / args.dt)}
        run.update(_child("run", args.duration, args.dt, interval, args.headway))
        runs.append(run)
        need = SimulationLog.bytes_needed(rows, args.vehicles)
        case: dict[str, object] = {"log_interval_s": interval, "rows": rows,
                                   "vehicles_on_road": args.vehicles, "bytes_needed": need,
                                   "gib": round(need / GIB, 4),
                                   "meets_target": need <= TARGET_GIB * GIB}  # fmt: skip
        if not args.no_measure:
            case.update(_child("fill", rows, args.vehicles, interval))
        worst.append(case)
    if args.json:
        print(json.dumps({"machine": machine(), "target_gib": TARGET_GIB, "results": runs,
                          "worst_case": worst}))  # fmt: skip
        return
    print("machine:", ", ".join(f"{k} {v}" for k, v in machine().items()))
    print(f"\nC1, {args.duration:g} s, main-lane headway {args.headway:g} s, ramp flow, "
          f"dt {args.dt:g} s: the engine's log")  # fmt: skip
    print(f"{'interval':>8} {'vehicles':>8} {'rows':>7} {'columns':>7} {'nbytes':>13} {'GiB':>7}"
          f" {'<=0.6':>5} {'RSS growth':>13} {'peak RSS':>13} {'one column each':>15}")  # fmt: skip
    for r in runs:
        print(f"{r['log_interval_s']:>8} {r['vehicles']:>8} {r['rows']:>7} {r['slot_columns']:>7}"
              f" {_num(r['nbytes']):>13} {r['gib']:>7} {'yes' if r['meets_target'] else 'no':>5}"
              f" {_num(r['rss_growth_bytes']):>13} {_num(r['peak_rss_bytes']):>13}"
              f" {_num(r['dense_bytes']):>15}")  # fmt: skip
    print(f"\nworst case: {args.vehicles} vehicles on the road at once for {args.duration:g} s")
    print(f"{'interval':>8} {'rows':>7} {'bytes_needed':>14} {'GiB':>7} {'<=0.6':>5}"
          f" {'nbytes':>14} {'RSS growth':>14}")  # fmt: skip
    for c in worst:
        print(f"{c['log_interval_s']:>8} {c['rows']:>7} {_num(c['bytes_needed']):>14} "
              f"{c['gib']:>7} {'yes' if c['meets_target'] else 'no':>5}"
              f" {_num(c.get('nbytes')):>14} {_num(c.get('rss_growth_bytes')):>14}")  # fmt: skip


if __name__ == "__main__":
    main()
