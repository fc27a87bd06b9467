"""Sweep rate: runs per minute on the local machine.

Runs a 12-cell sweep (2 x 2 headways x 3 penetrations around Condition 1) with FIFO and HCOMC,
one seed, into a temporary store, with 1 worker and with all cores; only ``run_sweep`` is
timed (fresh store each time, so nothing is skipped).

    python benchmarks/sweep_rate.py [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from throughput import machine

from hcomc.experiments.sweep import expand, run_sweep
from hcomc.experiments.sweep_spec import SweepGrid, SweepSpec


def measure(workers: int) -> dict[str, float]:
    """Runs per minute of the benchmark sweep with ``workers`` local processes."""
    spec = SweepSpec(
        name="bench", base="C1", configurations=["FIFO", "HCOMC"], seeds=1,
        grid=SweepGrid(mean_headway_main_1=[3.0, 5.0], mean_headway_main_2=[3.0, 5.0],
                       cav_penetration=[0.3, 0.6, 0.9]),
    )  # fmt: skip
    n = len(expand(spec))
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        run_sweep(spec, Path(tmp), workers=workers)
        wall = time.perf_counter() - start
    return {"workers": workers, "runs": n, "wall_s": round(wall, 2),
            "runs_per_min": round(n / wall * 60.0, 1)}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows = [measure(1), measure(os.cpu_count() or 1)]
    if args.json:
        print(json.dumps({"machine": machine(), "results": rows}))
        return
    print("machine:", ", ".join(f"{k} {v}" for k, v in machine().items()))
    print(f"{'workers':>7} {'runs':>5} {'wall [s]':>9} {'runs/min':>9}")
    for r in rows:
        print(f"{r['workers']:>7} {r['runs']:>5} {r['wall_s']:>9} {r['runs_per_min']:>9}")


if __name__ == "__main__":
    main()
