"""The virtual induction loops (hcomc.metrics.detectors) against SUMO's own E1 detectors on
one SUMO run: SUMO writes its loops' output and the run's FCD trajectories; our loops,
measured on those trajectories read back, give the same totals and speeds."""

from __future__ import annotations

import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from hcomc.config import ScenarioConfig
from hcomc.metrics.detectors import detector_table
from hcomc.road import Lane

POSITIONS = (400.0, 1200.0)
PERIOD = 10.0  # [s]: SUMO's intervals start at 0, ours after the warm-up (a multiple of it)


def _loops(config: ScenarioConfig, out: Path) -> Path:
    from hcomc.sumo.network import edge_at, sumo_lane_of

    lines = ["<additional>"]
    for x in POSITIONS:
        for lane in (Lane.MAIN_1, Lane.MAIN_2):
            edge = edge_at(config, x, lane)
            lines.append(
                f'  <inductionLoop id="x{x:g}_l{int(lane)}" lane="{edge.id}_'
                f'{sumo_lane_of(edge, lane)}" pos="{x - edge.x0:.3f}" period="{PERIOD:g}" '
                f'file="{out.name}"/>'
            )
    path = out.parent / "loops.add.xml"
    path.write_text("\n".join([*lines, "</additional>"]) + "\n", encoding="utf-8")
    return path


@pytest.mark.slow
def test_our_loops_count_what_sumos_loops_count(c1: ScenarioConfig, c1_scenario: Path):
    from hcomc.sumo import sumo_binary
    from hcomc.sumo.fcd import read_fcd

    folder = c1_scenario.parent
    fcd, e1 = folder / "loops-fcd.xml", folder / "e1.xml"
    subprocess.run(
        [sumo_binary("sumo"), "-c", str(c1_scenario), "--no-step-log", "true",
         "--additional-files", str(_loops(c1, e1)), "--fcd-output", str(fcd)],
        check=True, capture_output=True, timeout=600,
    )  # fmt: skip
    log, _ = read_fcd(fcd, c1)
    ours = detector_table(log, POSITIONS, interval=c1.duration, lanes=(1, 2))
    assert len(ours) == 2 * len(POSITIONS)
    assert c1.warmup % PERIOD == 0
    theirs: dict[str, list[ET.Element]] = {}
    for e in ET.parse(e1).getroot().iter("interval"):
        if float(e.get("begin", "nan")) >= c1.warmup:  # measured time only
            theirs.setdefault(str(e.get("id")), []).append(e)
    compared = 0
    for row in ours.itertuples():
        sumo = theirs[f"x{row.x:g}_l{row.lane}"]
        n = [int(float(str(e.get("nVehContrib")))) for e in sumo]
        # SUMO counts a vehicle when its rear has left the loop, we when its front reaches
        # it: at most the vehicle on the loop at the end of the run differs
        assert abs(row.count - sum(n)) <= 1, (row.x, row.lane, row.count, n)
        speed = sum(k * float(str(e.get("speed"))) for k, e in zip(n, sumo, strict=True))
        occupancy = np.mean([float(str(e.get("occupancy"))) for e in sumo])
        assert row.speed == pytest.approx(speed / sum(n), abs=0.2)
        assert row.occupancy == pytest.approx(occupancy, rel=0.1)
        compared += 1
    assert compared == 2 * len(POSITIONS)
