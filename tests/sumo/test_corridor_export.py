"""`hcomc export sumo corridor`: the network against the road's sections, the flows against
the demand profiles, a clean SUMO run and the command line."""

from __future__ import annotations

import math
import subprocess
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.corridor import Corridor, detector_positions, load_corridor, sections

sumolib = pytest.importorskip("sumolib")

END = 900.0  # [s] of the SUMO run: the mainline demand ramps from 2400 to 3000 veh/h


@pytest.fixture(scope="module")
def corridor() -> Corridor:
    return load_corridor("corridor")


@pytest.fixture(scope="module")
def exported(corridor: Corridor, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The `corridor` preset exported to SUMO."""
    from hcomc.sumo.corridor import export_corridor

    return export_corridor(corridor, tmp_path_factory.mktemp("corridor") / "d").directory


def test_edges_have_the_sections_lane_counts_and_extents(
    corridor: Corridor, exported: Path
) -> None:
    net = sumolib.net.readNet(str(exported / "net.xml"))
    width = corridor.road.lane_width
    found = sections(corridor.road)
    assert len([e for e in net.getEdges() if e.getID().startswith("main_")]) == len(found) == 21
    for i, s in enumerate(found):
        edge = net.getEdge(f"main_{i}")
        assert edge.getLaneNumber() == s.total_lanes, edge.getID()
        assert edge.getLength() == pytest.approx(s.length, abs=1e-2)
        assert edge.getSpeed() == pytest.approx(s.speed_limit, abs=1e-3)
        for index, lane in enumerate(edge.getLanes()):
            (xa, ya), (xb, _) = lane.getShape()[0], lane.getShape()[-1]
            assert (xa, xb) == pytest.approx((s.x0, s.x1), abs=1e-2)
            # mainline lane k (from the right) at y = (k + 1/2) W on every section,
            # ramp lanes to its right
            assert ya == pytest.approx((index - s.ramp_lanes + 0.5) * width, abs=1e-2)
    for ramp in (*corridor.road.on_ramps, *corridor.road.off_ramps):
        edge = net.getEdge(ramp.id)
        assert edge.getLaneNumber() == ramp.lanes
        assert edge.getLength() == pytest.approx(ramp.ramp_length, abs=1e-2)


def _links(net: object, edge_id: str) -> set[tuple[str, int, int]]:
    edge = net.getEdge(edge_id)  # type: ignore[attr-defined]
    return {
        (to.getID(), c.getFromLane().getIndex(), c.getToLane().getIndex())
        for to, conns in edge.getOutgoing().items()
        for c in conns
    }


def test_ramps_join_and_leave_on_the_right(corridor: Corridor, exported: Path) -> None:
    net = sumolib.net.readNet(str(exported / "net.xml"))
    found = sections(corridor.road)
    index = {s.ramp: i for i, s in enumerate(found) if s.ramp is not None}
    for ramp in corridor.road.on_ramps:
        i = index[ramp.id]
        # the ramp's lane becomes the acceleration lane (SUMO lane 0) ...
        assert _links(net, ramp.id) == {(f"main_{i}", 0, 0)}
        # ... which ends: only the three mainline lanes continue, shifted down by one
        assert _links(net, f"main_{i}") == {(f"main_{i + 1}", k + 1, k) for k in range(3)}
        # and the upstream mainline feeds only the mainline lanes
        assert _links(net, f"main_{i - 1}") == {(f"main_{i}", k, k + 1) for k in range(3)}
    for off in corridor.road.off_ramps:
        i = index[off.id]
        # the deceleration lane opens without a predecessor and leads onto the ramp
        assert _links(net, f"main_{i - 1}") == {(f"main_{i}", k, k + 1) for k in range(3)}
        assert _links(net, f"main_{i}") == {(off.id, 0, 0)} | {
            (f"main_{i + 1}", k + 1, k) for k in range(3)
        }
        assert _links(net, off.id) == set()


def _flow_counts(path: Path) -> Counter[str]:
    """Vehicles each origin's flows insert, by SUMO's rule: one at begin + k 3600/vph < end."""
    counts: Counter[str] = Counter()
    for flow in ET.parse(path).getroot().iter("flow"):
        period = 3600.0 / float(flow.get("vehsPerHour", "nan"))
        span = float(flow.get("end", "nan")) - float(flow.get("begin", "nan"))
        counts[flow.get("id", "").split("_")[0]] += math.ceil(span / period - 1e-9)
    return counts


def test_flows_carry_each_profile_to_the_vehicle(corridor: Corridor, exported: Path) -> None:
    counts = _flow_counts(exported / "routes.rou.xml")
    for origin, demand in corridor.demand.items():
        expected = demand.vehicles(0.0, corridor.corridor.duration)
        # each destination's count is its share of the integral rounded to a whole vehicle
        assert abs(counts[origin] - expected) <= 0.5 * len(demand.destinations), origin
    assert counts["main"] == pytest.approx(8800 / 3, abs=2.5)  # 933.3 + 1066.7 + 933.3


def test_vtypes_mix_classes_and_cavs(corridor: Corridor, exported: Path) -> None:
    root = ET.parse(exported / "routes.rou.xml").getroot()
    types = {t.get("id"): t.attrib for t in root.iter("vType")}
    assert set(types) == {"car_hdv", "car_cav", "truck_hdv", "truck_cav"}
    assert {t["carFollowModel"] for t in types.values()} == {"IDM"}
    assert float(types["car_hdv"]["tau"]) == 1.5
    assert float(types["car_cav"]["tau"]) == 1.0
    assert float(types["truck_hdv"]["length"]) == 16.5
    assert float(types["truck_cav"]["desiredMaxSpeed"]) == 25.0
    mix = next(d for d in root.iter("vTypeDistribution") if d.get("id") == "main_mix")
    names, shares = mix.get("vTypes", "").split(), mix.get("probabilities", "").split()
    probabilities = dict(zip(names, map(float, shares), strict=True))
    # 90 % cars, 10 % trucks, each 20 % CAVs
    assert probabilities == pytest.approx(
        {"car_hdv": 0.72, "car_cav": 0.18, "truck_hdv": 0.08, "truck_cav": 0.02}
    )


def test_detectors_cover_every_mainline_lane(corridor: Corridor, exported: Path) -> None:
    loops = list(ET.parse(exported / "detectors.add.xml").getroot().iter("inductionLoop"))
    positions = detector_positions(corridor)
    assert len(loops) == 3 * len(positions) == 81
    assert {loop.get("file") for loop in loops} == {"detectors.out.xml"}
    assert {loop.get("id") for loop in loops} == {
        f"det_{x:g}_{k}" for x in positions for k in range(3)
    }


@pytest.mark.slow
def test_sumo_runs_the_corridor_cleanly(corridor: Corridor, exported: Path, tmp_path: Path) -> None:
    from hcomc.sumo import sumo_binary

    trips = tmp_path / "trips.xml"
    done = subprocess.run(
        [sumo_binary("sumo"), "-c", str(exported / "corridor.sumocfg"), "--end", f"{END:g}",
         "--no-step-log", "true", "--tripinfo-output", str(trips),
         "--tripinfo-output.write-unfinished", "true"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "Warning" not in done.stderr, done.stderr
    assert "Error" not in done.stderr, done.stderr
    stats = ET.parse(exported / "statistics.xml").getroot()
    assert int(stats.find("teleports").get("total")) == 0
    assert int(stats.find("safety").get("collisions")) == 0
    departed: Counter[str] = Counter()
    early: Counter[str] = Counter()  # departed at least a minute before the end
    for trip in ET.parse(trips).getroot().iter("tripinfo"):
        depart = float(trip.get("depart", "-1"))
        if depart >= 0:
            departed[trip.get("id", "").split("_")[0]] += 1
            early[trip.get("id", "").split("_")[0]] += depart < END - 60
    for origin, demand in corridor.demand.items():
        expected = demand.vehicles(0.0, END)  # main 675, on1 81.3, ..., on5 75
        assert abs(departed[origin] - expected) <= 4 * math.sqrt(expected), origin
    # the detectors wrote every period, and the loops 50 m upstream of on1 (x = 750 m)
    # counted the mainline vehicles: at most all that entered, and nearly all that entered a
    # minute before the end (a loop misses a vehicle that changes onto its lane over it)
    intervals = list(ET.parse(exported / "detectors.out.xml").getroot().iter("interval"))
    assert len(intervals) == 81 * int(END / corridor.detectors.period)
    counted = sum(
        int(i.get("nVehContrib", "0")) for i in intervals if i.get("id", "").startswith("det_750_")
    )
    assert 0.95 * early["main"] <= counted <= departed["main"]


def test_cli_writes_the_corridor_and_refuses_bad_input(tmp_path: Path) -> None:
    out = tmp_path / "d"
    done = CliRunner().invoke(
        app, ["export", "sumo", "corridor", "--out", str(out), "--duration", "300", "--seed", "3"]
    )
    assert done.exit_code == 0, done.output
    written = load_corridor(out / "corridor.toml")
    assert (written.corridor.duration, written.corridor.seed) == (300.0, 3)
    cfg = ET.parse(out / "corridor.sumocfg").getroot()
    assert cfg.find("time/end").get("value") == "300"
    assert cfg.find("random_number/seed").get("value") == "3"
    counts = _flow_counts(out / "routes.rou.xml")
    assert counts["main"] == pytest.approx(
        written.demand["main"].vehicles(0.0, 300.0), abs=0.5 * 5
    )  # (2400 + 2600) / 2 veh/h over 300 s = 208.3
    assert {p.name for p in out.iterdir()} >= {
        "net.xml", "routes.rou.xml", "detectors.add.xml", "corridor.sumocfg", "manifest.json"
    }  # fmt: skip

    bad = tmp_path / "bad.toml"
    bad.write_text('base = "corridor"\n[corridor]\n[road]\nlanes = 0\n', encoding="utf-8")
    target = tmp_path / "never"
    refused = CliRunner().invoke(app, ["export", "sumo", str(bad), "--out", str(target)])
    assert refused.exit_code == 2
    assert "key 'road.lanes' = 0: allowed: 1 <= lanes <= 6" in refused.output
    assert len(refused.output.strip().splitlines()) == 1
    assert not target.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".corridor-")]
    unknown = CliRunner().invoke(app, ["export", "sumo", "corridr", "--out", str(target)])
    assert unknown.exit_code == 2
    assert (
        "allowed: a condition (C1, C2, C3, C4, C5, platoon), a corridor (corridor, paper, "
        "paper-C1, paper-C2, paper-C3, paper-C4, paper-C5)"
    ) in unknown.output.replace("\n", "")
    assert not target.exists()


def test_cli_exports_a_corridor_file_based_on_the_paper_road(tmp_path: Path) -> None:
    source = tmp_path / "short.toml"
    source.write_text('base = "paper"\n[corridor]\nduration = 120.0\n', encoding="utf-8")
    out = tmp_path / "paper"
    done = CliRunner().invoke(app, ["export", "sumo", str(source), "--out", str(out)])
    assert done.exit_code == 0, done.output
    net = sumolib.net.readNet(str(out / "net.xml"))
    assert [net.getEdge(f"main_{i}").getLaneNumber() for i in range(3)] == [2, 3, 2]
    assert net.getEdge("ramp").getLength() == pytest.approx(450.0)
