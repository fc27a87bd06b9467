"""The browser replay of corridor-engine runs: the road drawn from the corridor (one shape per
lane stretch), every sample of trajectories.csv in the packed arrays, the merges of
merges.csv on the timeline, two runs of one corridor side by side, the one-line refusals,
and the page in headless Chromium (where the vehicles are drawn, no motion across lanes)."""

from __future__ import annotations

import base64
import json
import math
import re
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import hcomc
from hcomc.cli import app
from hcomc.corridor import Corridor, load_corridor
from hcomc.metrics.corridor import simulate_corridor
from hcomc.road import KEY_ROLES
from hcomc.sim.log import EventKind
from hcomc.viz.replay.browser import Chromium, find_chromium
from hcomc.viz.replay.pack import STEPS

runner = CliRunner()
needs_chromium = pytest.mark.skipif(
    find_chromium() is None,
    reason="chromium is not installed (CI installs Debian's package in .ci/run)",
)

CORRIDOR = """
[corridor]
name = "replay-test"
duration = 40.0
seed = 1

[road]
lanes = 3
length = 3000.0
on_ramps = [{ id = "in1", x = 600.0, lanes = 2 }, { id = "in2", x = 2000.0 }]
off_ramps = [{ id = "out1", x = 1300.0 }]
lane_drops = [{ x = 1700.0, lanes = 2 }]
speed_limits = [{ x0 = 2400.0, x1 = 2800.0, speed = 25.0 }]

[demand.main]
flow = [[0.0, 2400.0]]
cav_share = 0.3
destinations = { exit = 0.8, out1 = 0.2 }

[demand.in1]
flow = [[0.0, 600.0]]
cav_share = 0.3

[demand.in2]
flow = [[0.0, 400.0]]
"""
"""Three lanes dropping to two, a two-lane on-ramp, an off-ramp, a second on-ramp and a
speed zone: every kind of lane stretch, in 40 s."""


def invoke(*args: str) -> Any:
    return runner.invoke(app, list(args))


def simulate(out: Path, source: str, *args: str) -> Path:
    result = invoke("simulate", source, *args, "--out", str(out), "--json")
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture(scope="module")
def corridor_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("corridor") / "replay-test.toml"
    path.write_text(CORRIDOR, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def runs(corridor_file: Path) -> dict[str, Path]:
    """The corridor with FIFO and HCOMC at every on-ramp, seed 1, sampled every 0.5 s."""
    sampled = ("--trajectory-interval", "0.5")
    return {
        c: simulate(corridor_file.parent / c, str(corridor_file), "--controller", c, *sampled)
        for c in ("fifo", "hcomc")
    }


@pytest.fixture(scope="module")
def page(runs: dict[str, Path]) -> Path:
    out = runs["fifo"].parent / "replay.html"
    result = invoke("replay", str(runs["fifo"]), str(runs["hcomc"]), "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "2 run(s)" in result.output
    return out


def page_data(path: Path) -> dict[str, Any]:
    text = path.read_text(encoding="utf-8")
    block = re.search(r'<script type="application/json" id="replay-data">(.*?)</script>', text,
                      re.S)  # fmt: skip
    assert block is not None
    return json.loads(block.group(1))


def decode(enc: dict[str, Any]) -> np.ndarray:
    data = np.frombuffer(base64.b64decode(enc["b64"]), dtype="<" + enc["dtype"])
    return data.reshape(enc["shape"])


def corridor_of(run: Path) -> Corridor:
    return Corridor.model_validate(json.loads((run / "manifest.json").read_text())["config"])


def lane_stretch_count(corridor: Corridor) -> int:
    """Lane stretches counted from the corridor's description alone: the mainline cut at every
    ramp end, lane drop and speed-zone boundary, each piece's mainline lanes plus the lanes of
    the ramp beside it, and each ramp road's lanes."""
    road = corridor.road
    cuts = {0.0, road.length, *(d.x for d in road.lane_drops)}
    for ramp in road.ramps:
        cuts |= {ramp.x, ramp.end}
    for zone in road.speed_limits:
        cuts |= {zone.x0, zone.x1}
    count = sum(r.lanes for r in road.ramps)
    for x0, x1 in pairwise(sorted(cuts)):
        mid = 0.5 * (x0 + x1)
        count += road.lanes_at(mid) + sum(r.lanes for r in road.ramps if r.x < mid < r.end)
    return count


def samples_of(run: Path) -> pd.DataFrame:
    return pd.read_csv(run / "trajectories.csv")


# ----------------------------------------------------------------------------- the road


def test_the_road_has_one_shape_per_lane_stretch(page: Path, runs: dict[str, Path]) -> None:
    corridor = corridor_of(runs["fifo"])
    road, width = corridor.road, corridor.road.lane_width
    for data in page_data(page)["runs"]:
        shapes = data["road"]
        lanes = [a for a in shapes["areas"] if a["surface"] != "zone"]
        zones = [a for a in shapes["areas"] if a["surface"] == "zone"]
        assert len(lanes) == lane_stretch_count(corridor) == 33
        assert len(zones) == len(road.on_ramps)
        # each ramp road slopes away from the mainline, down to ramp_length * sin(atan(0.1))
        sloped = [a for a in lanes if a["dy0"] or a["dy1"]]
        assert len(sloped) == sum(r.lanes for r in road.ramps)
        drop = -450.0 * math.sin(math.atan(0.1))
        assert {round(min(a["dy0"], a["dy1"]), 6) for a in sloped} == {
            round(drop, 6),
            round(-300.0 * math.sin(math.atan(0.1)), 6),
        }
        # the lane that ends at the drop and each acceleration lane end with a solid line
        ends = {(m["x0"], m["y0"], m["y1"]) for m in shapes["markings"]
                if m["x0"] == m["x1"] and m["stroke"] == "solid"}  # fmt: skip
        assert (1700.0, 2 * width, 3 * width) in ends
        for ramp in road.on_ramps:
            for j in range(ramp.lanes):
                assert (ramp.end, -(j + 1) * width, -j * width) in ends
        assert shapes["lanes"] == {"0": 0.5 * width, "1": 1.5 * width, "2": 2.5 * width,
                                   "-1": -0.5 * width, "-2": -1.5 * width}  # fmt: skip
        assert shapes["bounds"][0] < road.on_ramps[0].x - 400.0
        assert shapes["bounds"][1] == road.length


# ----------------------------------------------------------------------------- the samples


def test_every_sample_of_trajectories_csv_is_packed(page: Path, runs: dict[str, Path]) -> None:
    for data, run in zip(page_data(page)["runs"], runs.values(), strict=True):
        corridor = corridor_of(run)
        assert json.loads((run / "manifest.json").read_text())["trajectory_interval"] == 0.5
        width, angle = corridor.road.lane_width, math.atan(0.1)
        samples, arrays = samples_of(run), data["arrays"]
        trips = pd.read_csv(run / "trips.csv").set_index("id")
        t = decode(arrays["t"])
        row = np.rint((samples["t"].to_numpy() - t[0]) / 0.5).astype(int)
        np.testing.assert_array_equal(t[row], samples["t"].to_numpy())
        col = decode(arrays["column"])[samples["id"].to_numpy()]
        assert (col >= 0).all()
        x = decode(arrays["x"])
        xs = x[row, col]
        np.testing.assert_array_equal(xs, samples["x"].to_numpy(dtype=np.float32))
        assert np.isnan(x).sum() == x.size - len(samples)  # one cell per sample, no more
        np.testing.assert_array_equal(decode(arrays["lane"])[row, col], samples["lane"])
        cell = {n: decode(arrays[n])[row, col] * arrays[n]["step"] for n in (*STEPS, "dx")}
        for name in ("v", "a"):
            np.testing.assert_allclose(cell[name], samples[name], atol=arrays[name]["step"])
        # on the mainline: the lane's centre line, heading 0, drawn at x
        main = (samples["lane"] >= 0).to_numpy()
        np.testing.assert_allclose(cell["y"][main], (samples["lane"][main] + 0.5) * width,
                                   atol=STEPS["y"])  # fmt: skip
        assert not cell["heading"][main].any()
        assert not cell["dx"][main].any()
        # on an on-ramp road, d metres before the junction: along the slanted road
        for ramp in corridor.road.on_ramps:
            on_road = (samples["x"] < ramp.x - 1.0) & (samples["lane"] < 0)
            on_road &= samples["id"].map(trips["origin"]).eq(ramp.id)
            assert on_road.any()
            d = ramp.x - samples["x"][on_road]
            lane_y = -(-samples["lane"][on_road] - 0.5) * width
            np.testing.assert_allclose(cell["y"][on_road], lane_y - d * math.sin(angle),
                                       atol=STEPS["y"])  # fmt: skip
            np.testing.assert_allclose(xs[on_road] + cell["dx"][on_road],
                                       ramp.x - d * math.cos(angle), atol=2e-3)  # fmt: skip
            np.testing.assert_allclose(cell["heading"][on_road], angle, atol=STEPS["heading"])
        kind = decode(arrays["kind"])
        np.testing.assert_array_equal(kind[trips.index], trips["cav"].astype(int))
        length = decode(arrays["length"])
        np.testing.assert_allclose(
            length[trips.index], [corridor.vehicles[c].length for c in trips["vclass"]]
        )


def test_the_merges_are_on_the_timeline(page: Path, runs: dict[str, Path]) -> None:
    for data, run in zip(page_data(page)["runs"], runs.values(), strict=True):
        merges = pd.read_csv(run / "merges.csv").sort_values("zone_time", kind="stable")
        events = data["events"]
        assert events["zone_t"] == merges["zone_time"].tolist()
        assert events["zone_vr"] == merges["vr"].tolist()
        merged = merges[merges["merged"]]
        assert len(merged) >= 3
        marks = [k for k, kind in enumerate(events["kind"]) if kind == EventKind.MERGE]
        assert sorted((events["t"][k], events["vehicle"][k]) for k in marks) == sorted(
            zip(merged["merge_time"], merged["vr"], strict=True)
        )
        for k in marks:
            row = merged[merged["vr"] == events["vehicle"][k]].iloc[0]
            text = events["text"][k]
            assert f"VR {row['vr']} ({row['ramp']}" in text
            assert f"{row['merge_position']:.1f} m past the start of the acceleration lane" in text
            if row["vmc"] >= 0:
                assert f"VMC {row['vmc']}" in text
        # the key vehicles take their roles from VR's entry into the control zone
        roles = data["roles"]
        for row in merges.itertuples():
            group = {"VR": row.vr, **{r: getattr(row, r.lower()) for r in KEY_ROLES[1:]}}
            entry = {KEY_ROLES[roles["role"][k]]: roles["vehicle"][k]
                     for k in range(len(roles["vehicle"]))
                     if roles["t0"][k] == row.zone_time and roles["vr"][k] == row.vr}  # fmt: skip
            assert entry == {r: v for r, v in group.items() if v >= 0}
        table = data["merges"]
        assert [m["vr"] for m in table] == merges["vr"].tolist()
        assert [m["merged"] for m in table] == merges["merged"].tolist()


def test_two_runs_of_one_corridor_side_by_side(page: Path, runs: dict[str, Path]) -> None:
    data = page_data(page)
    assert [r["title"] for r in data["runs"]] == [
        "FIFO · replay-test · seed 1",
        "HCOMC (nsga2) · replay-test · seed 1",
    ]
    first, second = data["runs"]
    assert first["road"] == second["road"]
    assert first["vehicles"] == second["vehicles"]  # the same seed: the same vehicles
    assert first["lane_jumps"] is second["lane_jumps"] is True
    text = page.read_text(encoding="utf-8")
    assert not re.search(r"\b(?:src|href)\s*=", text), "the page loads nothing"


def test_python_api_takes_corridor_runs(runs: dict[str, Path], corridor_file: Path) -> None:
    page = hcomc.replay([runs["fifo"], runs["hcomc"]], titles=["a", "b"])
    assert '"title":"a"' in page.html
    run = simulate_corridor(load_corridor(str(corridor_file)), duration=10.0,
                            trajectory_interval=0.5)  # fmt: skip
    (data,) = json.loads(
        re.search(r'id="replay-data">(.*?)</script>', hcomc.replay(run).html, re.S).group(1)
    )["runs"]
    assert data["title"] == "no controller · replay-test · seed 1"
    assert decode(data["arrays"]["t"])[-1] == pytest.approx(run.trajectories["t"].max())


# ----------------------------------------------------------------------------- refusals


@pytest.fixture(scope="module")
def others(runs: dict[str, Path], corridor_file: Path) -> dict[str, Path]:
    """A corridor run without trajectories, a run of another corridor road and a scenario
    run, 5 s each."""
    base = corridor_file.parent
    return {
        "BARE": simulate(base / "bare", str(corridor_file), "--duration", "5"),
        "OTHER": simulate(base / "other", str(corridor_file), "--duration", "5",
                          "--set", "road.length=3200", "--trajectory-interval", "0.5"),
        "SCENARIO": simulate(base / "c2", "C2", "--duration", "5"),
    }  # fmt: skip


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["BARE"], "has no trajectories.csv"),
        (["FIFO", "SCENARIO"], "is a scenario run and run"),
        (["SCENARIO", "FIFO"], "is a corridor run and run"),
        (["FIFO", "OTHER"], "whose road differs from that of run"),
    ],
)
def test_bad_corridor_input_is_a_one_line_error(
    runs: dict[str, Path], others: dict[str, Path], tmp_path: Path, args: list[str],
    message: str,
) -> None:  # fmt: skip
    where = {"FIFO": runs["fifo"], **others}
    result = invoke("replay", *(str(where[a]) for a in args), "--out", str(tmp_path / "x.html"))
    assert result.exit_code == 2
    assert message in result.output
    assert len(result.output.strip().splitlines()) == 1, result.output
    assert not (tmp_path / "x.html").exists()
    if args == ["BARE"]:
        assert "--trajectory-interval S" in result.output
    with pytest.raises(ValueError, match=re.escape(message)):
        hcomc.replay([where[a] for a in args])


# ----------------------------------------------------------------------------- in Chromium


@needs_chromium
def test_the_page_draws_the_samples(page: Path, runs: dict[str, Path]) -> None:
    samples = {k: samples_of(run) for k, run in enumerate(runs.values())}
    with Chromium(1280, 900) as browser:
        browser.open(page.resolve().as_uri())
        assert browser.evaluate("hcomcReplay.ready") is True
        for t in (12.0, 25.5):
            browser.evaluate(f"hcomcReplay.seek({t!r})")
            for k, frame in samples.items():
                now = frame[np.isclose(frame["t"], t)]
                drawn = browser.evaluate(
                    f"{now['id'].tolist()}.map((i) => hcomcReplay.vehicleAt(i, {k}))"
                )
                for (_, s), d in zip(now.iterrows(), drawn, strict=True):
                    if s["lane"] >= 0:  # on the mainline: at x on its lane's centre line
                        assert d["x"] == pytest.approx(s["x"], abs=1e-3)
                        assert d["y"] == pytest.approx((s["lane"] + 0.5) * 3.75, abs=1e-3)
                        assert d["heading"] == 0
                    text = browser.evaluate(f"hcomcReplay.hover({int(s['id'])}, {k})")
                    shown = float(re.search(r" x (-?[\d.]+) m", text).group(1))
                    assert shown == pytest.approx(s["x"], abs=0.006)
                    assert f"lane {int(s['lane'])}" in text
        # a lane change is a jump: half-way between two samples the vehicle keeps its lane
        frame = samples[0].sort_values(["id", "t"])
        change = frame[(frame["id"].diff() == 0) & (frame["lane"].diff() != 0)
                       & (frame["lane"] >= 0) & (frame["lane"].shift() >= 0)].iloc[0]  # fmt: skip
        before = frame.loc[frame.index[frame.index.get_loc(change.name) - 1]]
        browser.evaluate(f"hcomcReplay.seek({float(before['t']) + 0.25!r})")
        d = browser.evaluate(f"hcomcReplay.vehicleAt({int(change['id'])}, 0)")
        assert d["y"] == pytest.approx((before["lane"] + 0.5) * 3.75, abs=1e-3)
        assert before["x"] < d["x"] < change["x"]  # moving along it
        first = pd.read_csv(runs["fifo"] / "merges.csv").sort_values("zone_time").iloc[0]
        assert browser.evaluate("hcomcReplay.keyVehicle()") == first["vr"]
        assert browser.console_errors == []


@needs_chromium
def test_screenshot_of_a_corridor_replay(runs: dict[str, Path], tmp_path: Path) -> None:
    png = tmp_path / "corridor.png"
    result = invoke("replay", str(runs["fifo"]), "--out", str(tmp_path / "r.html"),
                    "--screenshot", str(png))  # fmt: skip
    assert result.exit_code == 0, result.output
    merges = pd.read_csv(runs["fifo"] / "merges.csv")
    expected = merges.loc[merges["merged"], "merge_time"].min() - 1.5  # half a lane change
    assert f"(t = {expected:.1f} s)" in result.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
