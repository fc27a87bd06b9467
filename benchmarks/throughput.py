"""Simulation throughput: vehicle-steps per second with no merge controller.

Condition 1 traffic (5 s / 5 s headways, 90 % CAVs) on a mainline stretched so that about
N vehicles are on the road at once (N = 100, 500, 2000 by default). Only ``run()`` is timed:
demand generation and allocation are excluded. Prints the figures and the machine's facts;
``--json`` prints one JSON object.

    python benchmarks/throughput.py [--json] [--sizes 100 500 2000] [--duration 60]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

import numpy as np

import hcomc
from hcomc.config import ScenarioConfig, load_config
from hcomc.sim.engine import Simulation

SPACING = 5.0 * 30.0  # mean front-to-front spacing per lane at C1 headway and speed [m]


def machine() -> dict[str, object]:
    """Facts about the machine the figures come from."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            cpu = next(line.split(":", 1)[1].strip() for line in fh if "model name" in line)
    except (OSError, StopIteration):
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "hcomc": hcomc.__version__,
    }


def scene_config(n: int, duration: float) -> ScenarioConfig:
    """Condition 1 with the mainline stretched so that about ``n`` vehicles are on the road."""
    length = max(1500.0, n / 2 * SPACING)
    road = {"length": length, "accel_lane_start": 700.0, "accel_lane_end": 950.0}
    return load_config("C1", duration=duration, warmup=0.0, road=road)


def measure(n: int, duration: float, seed: int = 0) -> dict[str, float]:
    """Vehicle-steps/s of one run with about ``n`` vehicles on the road."""
    sim = Simulation(scene_config(n, duration), seed)
    start = time.perf_counter()
    sim.run()
    wall = time.perf_counter() - start
    steps = sim.n_steps
    return {
        "vehicles": round(sim.vehicle_steps / steps),
        "steps": steps,
        "vehicle_steps": sim.vehicle_steps,
        "wall_s": round(wall, 3),
        "vehicle_steps_per_s": round(sim.vehicle_steps / wall),
        "us_per_step": round(wall / steps * 1e6, 1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 500, 2000])
    parser.add_argument("--duration", type=float, default=60.0, help="simulated seconds per run")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    measure(min(args.sizes), args.duration)  # load the compiled code from its cache (untimed)
    rows = [measure(n, args.duration) for n in args.sizes]
    if args.json:
        print(json.dumps({"machine": machine(), "results": rows}))
        return
    print("machine:", ", ".join(f"{k} {v}" for k, v in machine().items()))
    print(
        f"{'vehicles':>9} {'steps':>6} {'veh-steps':>10} {'wall [s]':>9} {'veh-steps/s':>12}"
        f" {'us/step':>8}"
    )
    for r in rows:
        print(
            f"{r['vehicles']:>9} {r['steps']:>6} {r['vehicle_steps']:>10} {r['wall_s']:>9}"
            f" {r['vehicle_steps_per_s']:>12,} {r['us_per_step']:>8}"
        )


if __name__ == "__main__":
    main()
