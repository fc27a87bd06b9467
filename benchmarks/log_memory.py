"""Memory of a simulation log: a 1-hour run with 2000 vehicle slots, per logging interval.

For each logging interval the log the engine would allocate (``duration / dt`` steps, every
``log_interval / dt``-th logged, plus the row at t = 0) is sized with
``SimulationLog.bytes_needed`` (the figure the ``log_memory_limit`` check uses), then built
for real in a fresh child process: allocated, every row written with ``record`` (random
states, about 60 % of the slots active) so that every page is touched, and measured as
``log.nbytes`` and as the growth of the process's resident memory (VmRSS; Linux only).
Prints the figures and the machine's facts; ``--json`` prints one JSON object.

    python benchmarks/log_memory.py [--json] [--intervals 0.1 0.2 0.3 0.5 1.0]
        [--duration 3600] [--vehicles 2000] [--dt 0.1] [--no-measure]
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


def child(rows: int, vehicles: int, interval: float) -> dict[str, object]:
    """Allocate and fill one log in this process; its sizes and resident-memory growth."""
    rng = np.random.default_rng(0)
    states = rng.uniform(0.0, 1500.0, (5, vehicles))
    lane = rng.integers(0, 3, vehicles)
    rss0 = _vm_kib("VmRSS")
    start = time.perf_counter()
    log = SimulationLog.allocate(
        rows,
        vehicles,
        dt=interval,
        kind=np.ones(vehicles, dtype=np.int8),
        length=np.full(vehicles, 5.0),
        width=np.full(vehicles, 1.8),
    )
    for k in range(rows):
        active = rng.random(vehicles) < 0.6
        log.record(k, k * interval, *states, lane=lane, active=active)
    wall = time.perf_counter() - start
    rss1 = _vm_kib("VmRSS")
    grown = None if rss0 is None or rss1 is None else (rss1 - rss0) * 1024
    return {
        "nbytes": log.nbytes,
        "rss_growth_bytes": grown,
        "fill_wall_s": round(wall, 2),
        "dtypes": {name: str(getattr(log, name).dtype) for name in ("t", "x", "lane", "active")},
    }


def measure(rows: int, vehicles: int, interval: float) -> dict[str, object]:
    """Run :func:`child` in a fresh interpreter so resident-memory growth is the log's alone."""
    cmd = [sys.executable, __file__, "--child", str(rows), str(vehicles), str(interval)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    result: dict[str, object] = json.loads(out)
    return result


def _num(value: object) -> str:
    return f"{value:,}" if isinstance(value, int) else "-"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--intervals", type=float, nargs="+", default=[0.1, 0.2, 0.3, 0.5, 1.0])
    parser.add_argument("--duration", type=float, default=3600.0, help="measured seconds")
    parser.add_argument("--vehicles", type=int, default=2000, help="vehicle slots N")
    parser.add_argument("--dt", type=float, default=0.1, help="simulation step [s]")
    parser.add_argument("--no-measure", action="store_true", help="sizes only, allocate nothing")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        rows, vehicles, interval = int(args.child[0]), int(args.child[1]), float(args.child[2])
        print(json.dumps(child(rows, vehicles, interval)))
        return

    results = []
    for interval in args.intervals:
        rows = log_rows(args.duration, args.dt, interval)
        need = SimulationLog.bytes_needed(rows, args.vehicles)
        row: dict[str, object] = {
            "log_interval_s": interval,
            "every_kth_step": round(interval / args.dt),
            "rows": rows,
            "vehicles": args.vehicles,
            "bytes_needed": need,
            "gib": round(need / GIB, 4),
            "meets_target": need <= TARGET_GIB * GIB,
        }
        if not args.no_measure:
            row.update(measure(rows, args.vehicles, interval))
        results.append(row)
    if args.json:
        print(json.dumps({"machine": machine(), "target_gib": TARGET_GIB, "results": results}))
        return
    print("machine:", ", ".join(f"{k} {v}" for k, v in machine().items()))
    print(f"{args.duration:g} s, {args.vehicles} vehicle slots, dt {args.dt:g} s")
    print(
        f"{'interval':>8} {'k':>3} {'rows':>7} {'bytes_needed':>14} {'GiB':>7} {'<=0.6':>5}"
        f" {'nbytes':>14} {'RSS growth':>14} {'fill [s]':>8}"
    )
    for r in results:
        print(
            f"{r['log_interval_s']:>8} {r['every_kth_step']:>3} {r['rows']:>7}"
            f" {r['bytes_needed']:>14,} {r['gib']:>7} {'yes' if r['meets_target'] else 'no':>5}"
            f" {_num(r.get('nbytes')):>14} {_num(r.get('rss_growth_bytes')):>14}"
            f" {r.get('fill_wall_s', '-'):>8}"
        )


if __name__ == "__main__":
    main()
