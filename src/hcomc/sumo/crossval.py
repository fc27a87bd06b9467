"""Cross-validation of our engine against SUMO: same condition, same seeds, both engines.

:func:`traffic_stats` gives the uncontrolled traffic figures that must agree (mean speed per
main lane, flow past the merge); :func:`cross_validate` runs every configuration on both
engines through the experiment runner, so the rows are those of ``hcomc run``.
``python -m hcomc.sumo.crossval C1 --seeds 5`` prints the side-by-side table of docs/sumo.md,
``python -m hcomc.sumo.crossval C1,C2,C3,C4,C5 --traffic`` its uncontrolled traffic table
(:func:`traffic_table`).
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from hcomc.metrics.flow import throughput
from hcomc.road import Lane
from hcomc.sim.log import SimulationLog

__all__ = [
    "TrafficStats",
    "cross_validate",
    "markdown_table",
    "side_by_side",
    "traffic_stats",
    "traffic_table",
]


@dataclass(frozen=True, slots=True)
class TrafficStats:
    """Uncontrolled traffic figures of one run."""

    speed_lane_1: float  # mean speed of all logged lane-1 cells [m/s]
    speed_lane_2: float  # mean speed of all logged lane-2 cells [m/s]
    flow: float  # vehicles past accel_lane_end + 50 m per hour [veh/h]


def traffic_stats(log: SimulationLog) -> TrafficStats:
    """Mean speed per main lane and flow of a log."""

    def mean_speed(lane: Lane) -> float:
        cells = log.active & (log.lane == lane)
        return float(log.v[cells].astype(np.float64).mean())

    return TrafficStats(mean_speed(Lane.MAIN_1), mean_speed(Lane.MAIN_2), throughput(log))


def traffic_table(conditions: Iterable[str], seeds: Sequence[int]) -> str:
    """The uncontrolled traffic of ``conditions`` on both engines (no merge controller), as
    the Markdown table of docs/sumo.md: per condition and figure of :func:`traffic_stats`
    the means over ``seeds``, SUMO's mean relative difference and the largest absolute
    relative difference of a seed [%]."""
    from hcomc.config import load_config
    from hcomc.sim.engine import Simulation
    from hcomc.sumo.cosim import SumoSimulation

    names = {"speed_lane_1": "speed lane 1 [m/s]", "speed_lane_2": "speed lane 2 [m/s]",
             "flow": "flow [veh/h]"}  # fmt: skip
    lines = [
        "| condition | figure | ours | SUMO | difference (mean) | largest abs. difference of a "
        "seed [%] |",
        "|---|---|---|---|---|---|",
    ]
    for condition in conditions:
        config = load_config(condition, control={"controller": "none"})
        pairs = [  # (ours, SUMO's) per seed
            tuple(traffic_stats(engine(config, s).run()) for engine in (Simulation, SumoSimulation))
            for s in seeds
        ]
        for name, label in names.items():
            ours = np.array([getattr(a, name) for a, _ in pairs])
            sumo = np.array([getattr(b, name) for _, b in pairs])
            diff = (sumo - ours) / ours
            lines.append(
                f"| {condition} | {label} | {ours.mean():.4g} | {sumo.mean():.4g} | "
                f"{100 * diff.mean():+.2f} % | {100 * np.abs(diff).max():.2f} |"
            )
    return "\n".join(lines)


def cross_validate(
    condition: str, seeds: Iterable[int], configurations: Iterable[str]
) -> pd.DataFrame:
    """Runner rows of every configuration and seed on both engines (column ``engine``)."""
    from hcomc.experiments.runner import RunSpec, run_one

    rows = []
    for configuration in configurations:
        for seed in seeds:
            for engine in ("hcomc", "sumo"):
                row, _ = run_one(RunSpec(condition, configuration, seed, engine=engine))
                rows.append({**row, "engine": engine})
    return pd.DataFrame(rows)


def side_by_side(runs: pd.DataFrame, metrics: Iterable[str]) -> pd.DataFrame:
    """Mean of each metric per configuration and engine, with SUMO's relative difference."""
    means = runs.groupby(["configuration", "engine"], sort=False)[list(metrics)].mean()
    out = []
    for configuration in dict.fromkeys(runs["configuration"]):
        ours, sumo = means.loc[(configuration, "hcomc")], means.loc[(configuration, "sumo")]
        for metric in metrics:
            diff = (sumo[metric] - ours[metric]) / abs(ours[metric]) if ours[metric] else np.nan
            out.append({"configuration": configuration, "metric": metric, "hcomc": ours[metric],
                        "sumo": sumo[metric], "difference": diff})  # fmt: skip
    return pd.DataFrame(out)


def markdown_table(runs: pd.DataFrame, metrics: Iterable[str]) -> str:
    """Metric rows x configuration columns, ``ours / SUMO`` means over seeds (docs/sumo.md)."""
    table = side_by_side(runs, list(metrics))
    configurations = list(dict.fromkeys(table["configuration"]))
    lines = [
        "| metric | " + " | ".join(f"{c} ours | {c} SUMO" for c in configurations) + " |",
        "|---|" + "---|---|" * len(configurations),
    ]
    for metric, rows in table.groupby("metric", sort=False):
        cells = [f"{v:.4g}" for _, r in rows.iterrows() for v in (r["hcomc"], r["sumo"])]
        lines.append(f"| {metric} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _main() -> None:  # pragma: no cover - documentation helper
    from hcomc.metrics import METRICS

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("condition", help="a condition (with --traffic: several, comma-separated)")
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--configurations", default="FIFO,Game,HCOMC")
    parser.add_argument("--out", help="also write every run's row to this CSV file")
    parser.add_argument(
        "--traffic", action="store_true", help="the uncontrolled traffic table instead"
    )
    args = parser.parse_args()
    if args.traffic:
        print(traffic_table(args.condition.split(","), range(args.seeds)))
        return
    runs = cross_validate(args.condition, range(args.seeds), args.configurations.split(","))
    if args.out:
        runs.to_csv(args.out, index=False)
    print(markdown_table(runs, [m for m in METRICS if m in runs.columns]))


if __name__ == "__main__":  # pragma: no cover
    _main()
