"""Cross-validation of hcomc against SUMO on one corridor, no ramp control.

Both engines run the same corridor (``--corridor``, default the ``corridor`` preset) for
``--duration`` seconds from its start, with the same vehicles departing at the same times
(:mod:`hcomc.corridor.schedule`): hcomc with :func:`hcomc.metrics.corridor.simulate_corridor`,
SUMO with the exported scenario (:func:`hcomc.sumo.corridor.export_corridor`, run as the
``sumo`` program with ``--tripinfo-output``). Printed beside each other, with the relative
difference hcomc / SUMO − 1:

* per origin: vehicles arrived, mean travel time (arrival − insertion; SUMO's tripinfo
  ``duration``) and mean delay (hcomc: travel time minus the free-flow time; SUMO:
  ``timeLoss``);
* per cross-section of induction loops: vehicles counted over all mainline lanes after the
  first ``--warm`` seconds (both roads start empty), and the share of the rightmost lane.

    python benchmarks/corridor_validation.py [--corridor corridor] [--duration 3600]
                                             [--warm 300] [--json]
                                             [--sumo-vtype KEY=VALUE ...]
                                             [--sumo-option NAME=VALUE ...] [--keep DIR]

To find which of SUMO's model choices makes its traffic differ from hcomc's, SUMO's side can
be changed for one run while hcomc's stays as it is:

* ``--sumo-vtype KEY=VALUE`` (repeatable) sets attribute KEY of every vType of the exported
  ``routes.rou.xml`` to VALUE before SUMO runs, e.g. ``lcKeepRight=0`` or ``stepping=0.1``
  (LC2013 and IDM parameters; the export itself is not changed);
* ``--sumo-option NAME=VALUE`` (repeatable) adds ``--NAME VALUE`` to the ``sumo`` command
  line, which overrides the exported ``corridor.sumocfg``, e.g. ``lanechange.duration=0``;
* ``--keep DIR`` keeps SUMO's scenario and outputs (``tripinfo.xml``,
  ``detectors.out.xml``) in DIR instead of a temporary directory.

The changes applied are printed under the header and recorded under ``sumo_changes`` in the
JSON; without them SUMO runs the export unchanged. benchmarks/RESULTS.md ("Corridor") lists
the changes tried on the ``corridor`` preset's hour and what each does to the comparison.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pandas as pd

from hcomc import __version__
from hcomc.corridor import load_corridor
from hcomc.metrics.corridor import simulate_corridor
from hcomc.sim.manifest import git_revision
from hcomc.sumo import sumo_binary
from hcomc.sumo.corridor import export_corridor


def _pairs(items: list[str], what: str) -> dict[str, str]:
    """``["KEY=VALUE", ...]`` as a dict (a later KEY wins)."""
    pairs = {}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip().lstrip("-")
        if not sep or not key:
            raise SystemExit(f"{what}: expected KEY=VALUE, got {item!r}")
        pairs[key] = value.strip()
    return pairs


def _set_vtypes(routes: Path, attributes: dict[str, str]) -> None:
    """Set ``attributes`` on every vType of the route file ``routes``, in place."""
    if not attributes:
        return
    tree = ET.parse(routes)
    for vtype in tree.getroot().iter("vType"):
        vtype.attrib.update(attributes)
    tree.write(routes, encoding="UTF-8", xml_declaration=True)


def _sumo(
    corridor: Any, duration: float, folder: Path, vtype: dict[str, str], options: dict[str, str]
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """SUMO's trips (origin, destination, travel time, time loss) and loop counts, with the
    vType attributes ``vtype`` and the command-line options ``options`` applied."""
    scenario = export_corridor(corridor, folder)
    _set_vtypes(scenario.routes, vtype)
    trips = folder / "tripinfo.xml"
    extra = [arg for name, value in options.items() for arg in (f"--{name}", value)]
    done = subprocess.run(
        [sumo_binary("sumo"), "-c", str(scenario.sumocfg), "--end", f"{duration:g}",
         "--tripinfo-output", str(trips), "--no-step-log", "true", "--no-warnings", "true",
         *extra],
        check=False, capture_output=True, text=True,
    )  # fmt: skip
    if done.returncode:  # e.g. an unknown option or attribute: show SUMO's message
        raise SystemExit(f"sumo failed ({done.returncode}):\n{done.stderr}")
    rows = []
    for info in ET.parse(trips).getroot().iter("tripinfo"):
        origin, destination = info.get("id", "").split("_")[:2]  # flow ids: origin_dest_k.n
        rows.append({"origin": origin, "destination": destination,
                     "travel_time": float(info.get("duration", "nan")),
                     "delay": float(info.get("timeLoss", "nan"))})  # fmt: skip
    loops = []
    for interval in ET.parse(folder / "detectors.out.xml").getroot().iter("interval"):
        _, x, lane = interval.get("id", "").split("_")
        loops.append({"x": float(x), "lane": int(lane), "begin": float(interval.get("begin", 0)),
                      "count": float(interval.get("nVehContrib", 0))})  # fmt: skip
    return pd.DataFrame(rows), pd.DataFrame(loops)


def compare(
    name: str,
    duration: float | None,
    warm: float,
    vtype: dict[str, str] | None = None,
    options: dict[str, str] | None = None,
    keep: Path | None = None,
) -> dict[str, Any]:
    """Both engines on corridor ``name``; the comparison as JSON-ready tables. ``vtype`` and
    ``options`` change SUMO's side (module docstring); ``keep`` is a folder for its files."""
    corridor = load_corridor(name)
    duration = corridor.corridor.duration if duration is None else duration
    vtype, options = vtype or {}, options or {}
    with tempfile.TemporaryDirectory() as folder:
        where = Path(folder) if keep is None else keep
        sumo_trips, sumo_loops = _sumo(corridor, duration, where, vtype, options)
    run = simulate_corridor(corridor, duration=duration)
    ours = run.trips[run.trips.arrive.notna()]
    origins = []
    for origin in corridor.demand:
        a, b = ours[ours.origin == origin], sumo_trips[sumo_trips.origin == origin]
        origins.append({
            "origin": origin, "arrived": len(a), "arrived_sumo": len(b),
            "travel_time": a.travel_time.mean(), "travel_time_sumo": b.travel_time.mean(),
            "delay": a.delay.mean(), "delay_sumo": b.delay.mean(),
        })  # fmt: skip
    sections = []
    mine = run.detectors[run.detectors.begin >= warm]
    theirs = sumo_loops[sumo_loops.begin >= warm]
    for x, at in mine.groupby("x"):
        there = theirs[theirs.x == x]
        count, count_sumo = float(at["count"].sum()), float(there["count"].sum())
        sections.append({
            "x": float(x), "count": count, "count_sumo": count_sumo,
            "right_share": float(at[at.lane == 0]["count"].sum()) / count if count else None,
            "right_share_sumo": (float(there[there.lane == 0]["count"].sum()) / count_sumo
                                 if count_sumo else None),
        })  # fmt: skip
    return {
        "corridor": name, "duration": duration, "warm": warm, "hcomc_version": __version__,
        "git_revision": git_revision(), "missed_exits": int(run.summary()["missed_exit"]),
        "sumo_changes": {"vtype": vtype, "options": options},
        "origins": origins, "sections": sections,
    }  # fmt: skip


def _relative(a: float, b: float) -> str:
    return f"{a / b - 1:+.1%}" if b else "–"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corridor", default="corridor")
    parser.add_argument("--duration", type=float, default=None)
    parser.add_argument("--warm", type=float, default=300.0)
    parser.add_argument("--json", action="store_true")
    parser.add_argument(
        "--sumo-vtype",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="set a vType attribute of every SUMO vehicle type (repeatable)",
    )
    parser.add_argument(
        "--sumo-option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="add --NAME VALUE to the sumo command line (repeatable)",
    )
    parser.add_argument(
        "--keep",
        type=Path,
        default=None,
        metavar="DIR",
        help="keep SUMO's scenario and outputs in DIR",
    )
    args = parser.parse_args()
    if args.keep is not None and "," in str(args.keep):
        parser.error("--keep: SUMO reads a comma in an output path as a list of files")
    vtype = _pairs(args.sumo_vtype, "--sumo-vtype")
    options = _pairs(args.sumo_option, "--sumo-option")
    result = compare(args.corridor, args.duration, args.warm, vtype, options, args.keep)
    if args.json:
        sys.stdout.write(json.dumps(result) + "\n")
        return
    head = f"{result['corridor']}, {result['duration']:g} s, hcomc {result['hcomc_version']}"
    print(f"{head} ({result['git_revision']}); hcomc's missed exits: {result['missed_exits']}")
    changed = result["sumo_changes"]
    changes = [f"vType {k}={v}" for k, v in changed["vtype"].items()]
    changes += [f"--{k} {v}" for k, v in changed["options"].items()]
    if changes:
        print(f"SUMO changed: {', '.join(changes)}")
    print("origin   arrived (SUMO)   travel time [s] (SUMO, diff)   delay [s] (SUMO)")
    for o in result["origins"]:
        print(f"{o['origin']:<8} {o['arrived']:>5} ({o['arrived_sumo']:>5})   "
              f"{o['travel_time']:7.1f} ({o['travel_time_sumo']:7.1f}, "
              f"{_relative(o['travel_time'], o['travel_time_sumo'])})   "
              f"{o['delay']:6.1f} ({o['delay_sumo']:6.1f})")  # fmt: skip
    print(f"x [m]    vehicles after {result['warm']:g} s (SUMO, diff)   right-lane share (SUMO)")
    for s in result["sections"]:
        share, share_sumo = s["right_share"] or 0.0, s["right_share_sumo"] or 0.0
        diff = _relative(s["count"], s["count_sumo"])
        print(f"{s['x']:<8g} {s['count']:7.0f} ({s['count_sumo']:7.0f}, {diff})   "
              f"{share:.2f} ({share_sumo:.2f})")  # fmt: skip


if __name__ == "__main__":
    main()
