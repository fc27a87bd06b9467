"""CPU-seconds per run of the robustness campaign, per controller and per channel/shield
setting: the runs of ``hcomc faults`` (one process, after a warm-up run; process start-up and
the campaign's bookkeeping left out).

    python benchmarks/campaign_cost.py [--seeds 3] [--json]

Cells: C1, C3, C5 x FIFO, Game, HCOMC x no fault, brake-vmf x the three channel settings x
shield off/on, ``--seeds`` runs each; time by ``time.process_time``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from typing import Any

from hcomc.robustness.campaign import CampaignSpec, run_faulted


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="runs per cell")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = parser.parse_args()
    spec = CampaignSpec(conditions=("C1", "C3", "C5"), configurations=("FIFO", "Game", "HCOMC"),
                        faults=("none", "brake-vmf"), seeds=tuple(range(args.seeds)))  # fmt: skip
    run_faulted(spec.runs(spec.cells()[0])[0])  # compiled, imported, warm
    per_cell: dict[tuple[str, str, bool], list[float]] = {}
    for cell in spec.cells():
        start = time.process_time()
        for run in spec.runs(cell):
            run_faulted(run)
        per_cell.setdefault((cell[1], cell[3], cell[4]), []).append(
            (time.process_time() - start) / args.seeds
        )
    every = [x for values in per_cell.values() for x in values]
    result: dict[str, Any] = {
        "cpu_s_per_run": statistics.mean(every),
        "by_controller": {c: statistics.mean([x for (k, _, _), v in per_cell.items() if k == c
                                              for x in v]) for c in spec.configurations},
        "by_setting": {f"{k} {ch} shield {'on' if s else 'off'}": statistics.mean(v)
                       for (k, ch, s), v in per_cell.items()},
    }  # fmt: skip
    if args.json:
        print(json.dumps(result))
        return
    for name, value in result["by_setting"].items():
        print(f"{name:45s} {value:.4f} s")
    for name, value in result["by_controller"].items():
        print(f"{name:45s} {value:.4f} s")
    print(f"{'every run':45s} {result['cpu_s_per_run']:.4f} s")


if __name__ == "__main__":
    main()
