"""The ``corridor`` preset's hour over several seeds, without a merge controller and with one
at every on-ramp: what each run measured, one Markdown row per seed.

    python benchmarks/corridor_seeds.py [--corridor corridor] [--seeds 10]
                                        [--controllers none hcomc] [--duration 3600]

Per seed, for each controller (``a / b`` in the order given): vehicles arrived, missed exits,
the mainline's mean travel time, the merged share at each on-ramp (least and largest over the
ramps), the mean time from the control zone to the merge (ramp means, least and largest), the
5th percentile of the merge events' least time to collision (ramps, least and largest),
collisions, and for the controlled runs their decisions, fallbacks and wall time. The header
line names the corridor, duration, hcomc version and git revision.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from hcomc import __version__
from hcomc.corridor import load_corridor
from hcomc.metrics.corridor import simulate_corridor
from hcomc.sim.manifest import git_revision


def _span(values: list[float | None], digits: int) -> str:
    """``least–largest`` of the defined values (``–`` when none is)."""
    defined = [v for v in values if v is not None]
    if not defined:
        return "–"
    return f"{min(defined):.{digits}f}–{max(defined):.{digits}f}"


def measure(corridor: str, controller: str, seed: int, duration: float) -> dict[str, Any]:
    """One run's figures (module docstring)."""
    c = load_corridor(corridor, {"control.controller": controller})
    run = simulate_corridor(c, seed=seed, duration=duration)
    s = run.summary()
    ramps = s["on_ramps"].values()
    events = [r["merge_events"] for r in ramps]
    return {
        "arrived": s["arrived"] + s["missed_exit"], "missed": s["missed_exit"],
        "main": s["origins"]["main"]["mean_travel_time"],
        "merged": _span([r["merged_share"] for r in ramps], 3),
        "to_merge": _span([e["mean_time_to_merge"] for e in events], 1),
        "ttc": _span([e["min_ttc_p05"] for e in events], 2),
        "collisions": s["collisions"], "decisions": s["decisions"],
        "fallbacks": sum(e["fallbacks"] for e in events), "wall": run.wall_seconds,
        "not_inserted": s["not_inserted"],
    }  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corridor", default="corridor")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--controllers", nargs="+", default=["none", "hcomc"])
    parser.add_argument("--duration", type=float, default=3600.0)
    args = parser.parse_args(argv)
    print(f"{args.corridor}, {args.duration:g} s, controllers {' / '.join(args.controllers)}; "
          f"hcomc {__version__} ({git_revision()})")  # fmt: skip
    print("| seed | arrived | missed exits | not inserted | mean travel time main [s] | "
          "merged share, ramps | zone to merge [s], ramps | least TTC 5th pct. [s], ramps | "
          "collisions | decisions | fallbacks | wall [s] |")  # fmt: skip
    print("|" + "---|" * 12)
    for seed in range(args.seeds):
        rows = [measure(args.corridor, ctl, seed, args.duration) for ctl in args.controllers]

        def both(key: str, fmt: str = "{}", rows: list[dict[str, Any]] = rows) -> str:
            return " / ".join(fmt.format(r[key]) for r in rows)

        print(f"| {seed} | {both('arrived')} | {both('missed')} | {both('not_inserted')} | "
              f"{both('main', '{:.1f}')} | {both('merged')} | {both('to_merge')} | "
              f"{both('ttc')} | {both('collisions')} | {both('decisions')} | "
              f"{both('fallbacks')} | {both('wall', '{:.1f}')} |", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
