"""A stalled vehicle on the acceleration lane (``[[faults]]`` kind ``stalled_vehicle``): it
stands for the whole run, no controller plans for it, the ramp vehicles brake for it and
leave the lane before it, the rest of the traffic is the nominal run's, and every command
that runs a config runs it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import ConfigError, load_config
from hcomc.corridor import load_corridor
from hcomc.experiments.runner import RunSpec, make_simulation
from hcomc.metrics.corridor import simulate_corridor
from hcomc.metrics.ramp import ramp_summary
from hcomc.road import Kind
from hcomc.robustness.impairments import listeners_of
from hcomc.sim.engine import Simulation
from hcomc.sim.lane_table import ENDS_BLOCKED, L_END, L_ENDS, L_OPENS, MIN_CHANGE_LENGTHS
from hcomc.sim.log import EventKind
from hcomc.sim.stalled import acceleration_lanes
from hcomc.viz.replay.browser import Chromium, find_chromium

runner = CliRunner()

STALLED = {"kind": "stalled_vehicle", "position": 100.0}
"""Front bumper 100 m into the paper's 250 m acceleration lane (x = 800 m)."""


def _config(controller: str = "hcomc", **overrides: object):
    return load_config("C2", control={"controller": controller}, faults=[STALLED], **overrides)


def _run(config, seed: int = 1) -> Simulation:
    sim = make_simulation(config, seed)
    sim.run()
    return sim  # type: ignore[return-value]


@pytest.mark.parametrize("controller", ["fifo", "game", "hcomc"])
def test_it_stands_all_run_and_no_controller_plans_for_it(controller: str) -> None:
    """The stalled vehicle is the run's last vehicle, at x = 700 + 100 m from the first row
    to the last at speed 0; it is nobody's VR, no plan names it, the log marks its fault and
    nobody collides."""
    config = _config(controller)
    sim = _run(config)
    log = sim.log
    (i,) = sim.stalled.tolist()
    assert i == sim.demand.n - 1
    assert log.meta["stalled"] == [i]
    assert np.all(log.active[:, i])
    np.testing.assert_array_equal(log.x[:, i], config.road.accel_lane_start + 100.0)
    np.testing.assert_array_equal(log.v[:, i], 0.0)
    assert i not in sim.key_groups
    assert all(i not in (p.group.vr, p.cooperating) for p in sim.decisions)
    assert log.events_of(EventKind.FAULT)["vehicle"].tolist() == [i]
    assert log.events_of(EventKind.COLLISION).size == 0
    assert not log.events_of(EventKind.RAMP_WAIT)["vehicle"].tolist().count(i)


def test_the_controllers_see_the_road_as_built_the_engine_the_blocked_lane() -> None:
    """Closed form: the engine's acceleration lane ends 3 L + min_gap before the stalled
    vehicle's rear (800 - 5 - 15 - 2 = 778 m) and stops every vehicle in it; the road the
    controllers are given still ends at 950 m."""
    config = _config()
    sim = Simulation(config, 1)
    (code,) = acceleration_lanes(sim.lanes).tolist()
    length, gap = config.road.vehicle_length, config.lane_change.min_gap
    end = config.road.accel_lane_start + 100.0 - length - MIN_CHANGE_LENGTHS * length - gap
    assert sim.arrays.road_f[L_END, code] == pytest.approx(end)
    assert sim.arrays.road_int[L_ENDS, code] == ENDS_BLOCKED
    assert sim.ramps[0].accel_lane_end == config.road.accel_lane_end
    assert sim.lanes.floats[L_END, code] == config.road.accel_lane_end


@pytest.mark.parametrize("controller", ["fifo", "hcomc"])
def test_ramp_vehicles_merge_before_it_or_stop_where_they_can_steer_around_it(
    controller: str,
) -> None:
    """A continuous ramp demand (a ramp vehicle every 8 s on average, 150 s, three seeds):
    no ramp vehicle's centre is ever in the acceleration lane at or beyond the stalled
    vehicle's rear, none that stands there stands past the lane's blocked end, nobody
    collides, and most of them merge."""
    config = _config(controller, duration=150.0,
                     demand={"ramp": "flow", "ramp_mean_headway": 8.0})  # fmt: skip
    merged = entered = 0
    for seed in range(3):
        sim = _run(config, seed)
        log, (i,) = sim.log, sim.stalled.tolist()
        code = int(acceleration_lanes(sim.lanes)[0])
        end = float(sim.arrays.road_f[L_END, code])
        others = np.arange(log.x.shape[1]) != i
        in_lane = (log.lane == code) & log.active & others
        assert np.all(log.x[in_lane] < log.x[0, i] - config.road.vehicle_length)
        standing = in_lane & (log.v < 0.1) & (log.x > sim.lanes.floats[L_OPENS, code])
        assert np.all(log.x[standing] <= end + 1e-6)
        assert log.events_of(EventKind.COLLISION).size == 0
        summary = ramp_summary(log)
        merged, entered = merged + summary["merged"], entered + summary["vehicles"]
    assert entered >= 30
    assert merged >= 0.8 * entered


def test_the_rest_of_the_traffic_is_the_nominal_run_of_its_seed() -> None:
    """Same demand, same draws: until the controller's first decision (for a ramp vehicle
    that saw the stalled vehicle ahead from its release on, so the plans differ), every
    mainline vehicle moves exactly as in the nominal run of the seed; the undisturbed runs
    differ only by the stalled vehicle's column, which is never on the road."""
    nominal = load_config("C2", control={"controller": "fifo"})
    stalled = _config("fifo")
    a, b = _run(nominal, 4), _run(stalled, 4)
    n = a.demand.n
    ramp = np.flatnonzero(a.demand.lane == int(acceleration_lanes(a.lanes)[0]))
    first = min(a.log.meta["key_groups"][0]["t"], b.log.meta["key_groups"][0]["t"])
    rows = slice(0, int(np.searchsorted(a.log.t, first + 1e-9)))
    assert rows.stop > 100
    main = np.setdiff1d(np.arange(n), ramp)
    np.testing.assert_array_equal(a.log.x[rows][:, main], b.log.x[rows][:, main])
    np.testing.assert_array_equal(a.log.v[rows][:, main], b.log.v[rows][:, main])
    assert not np.array_equal(a.log.x[rows][:, ramp], b.log.x[rows][:, ramp])
    ua = Simulation(nominal, 4, counterfactual=True)
    ub = Simulation(stalled, 4, counterfactual=True)
    ua.run(), ub.run()
    np.testing.assert_array_equal(ua.log.x, ub.log.x[:, :n])
    assert not ub.log.active[:, n].any()


def test_a_stalled_run_has_an_undisturbed_run_of_its_own() -> None:
    """The stalled vehicle is a vehicle of both runs (the same log columns), so a stalled
    run does not share the nominal run's undisturbed run; other faults do."""
    nominal = RunSpec("C2", "FIFO", 3, {})
    braking = RunSpec("C2", "FIFO", 3, {"faults": ["brake-vmf"]})
    stalled = RunSpec("C2", "HCOMC", 3, {"faults": ["brake-vmf", "stalled"]})
    assert braking.reference_key() == nominal.reference_key()
    assert stalled.reference_key() != nominal.reference_key()
    assert stalled.reference_key() == RunSpec("C2", "FIFO", 3, {"faults": ["stalled"]}
                                              ).reference_key()  # fmt: skip


def test_hcomc_run_measures_a_stalled_run_through_the_cli(tmp_path: Path) -> None:
    """``hcomc run`` of a config file with the stalled vehicle: the paper's metrics against
    its own undisturbed run, the fault in every row."""
    path = tmp_path / "stalled.toml"
    path.write_text('base = "C2"\nduration = 60.0\n[[faults]]\nkind = "stalled_vehicle"\n'
                    "position = 120.0\n", encoding="utf-8")  # fmt: skip
    result = runner.invoke(app, ["run", str(path), "--controller", "fifo", "--seeds", "2",
                                 "--workers", "1", "--json"])  # fmt: skip
    assert result.exit_code == 0, result.output
    rows = json.loads(result.output.strip().splitlines()[-1])
    assert [r["fault_kinds"] for r in rows] == ["stalled_vehicle"] * 2
    assert all(r["merged"] for r in rows)


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("position = 300.0", "key 'faults[0].position' = 300.0: allowed: 24 to 250 m past"),
        ("position = 20.0", "key 'faults[0].position' = 20.0: allowed: 24 to 250 m past"),
        ("ramp = 1", "key 'faults[0].ramp' = 1: the road has 1 on-ramp(s); allowed: 0 to 0"),
    ],
)
def test_a_stalled_vehicle_off_the_lane_is_a_one_line_error(
    tmp_path: Path, text: str, named: str
) -> None:
    """A position beyond the acceleration lane or a ramp the road lacks: exit 2, one line
    naming the key, before any run."""
    path = tmp_path / "bad.toml"
    path.write_text(f'base = "C2"\n[[faults]]\nkind = "stalled_vehicle"\n{text}\n',
                    encoding="utf-8")  # fmt: skip
    result = runner.invoke(app, ["simulate", str(path), "--out", str(tmp_path / "out")])
    assert result.exit_code == 2
    (line,) = result.output.strip().splitlines()
    assert line.startswith(f"error: {named}")
    with pytest.raises(ConfigError, match=r"faults\[0\]"):
        Simulation(load_config(path), 0)


def test_a_corridor_stalls_a_vehicle_on_the_ramp_it_names(tmp_path: Path) -> None:
    """A corridor's ``[[faults]]`` put it on the acceleration lane of its ``ramp`` (the
    third, on3 at 4,800 m): it stands there all run and nobody drives into it."""
    road = tmp_path / "short.toml"
    road.write_text('base = "corridor"\n[corridor]\nduration = 240.0\n[[faults]]\n'
                    'kind = "stalled_vehicle"\nramp = 2\nposition = 120.0\n',
                    encoding="utf-8")  # fmt: skip
    corridor = load_corridor(road)
    measured = simulate_corridor(corridor, seed=0, listeners=listeners_of(corridor))
    log = measured.log
    (i,) = log.meta["stalled"]
    np.testing.assert_array_equal(log.x[:, i], 4800.0 + 120.0)
    np.testing.assert_array_equal(log.v[:, i], 0.0)
    assert log.events_of(EventKind.COLLISION).size == 0
    lane = int(log.lane[0, i])
    others = (log.lane == lane) & log.active & (np.arange(log.x.shape[1]) != i)
    assert others.any()  # ramp vehicles came along that lane ...
    assert np.all(log.x[others] < 4800.0 + 120.0 - 5.0)  # ... and none passed it in it
    assert i not in measured.trips["id"].tolist()  # nobody's trip, nobody waiting to enter


def test_a_corridor_replay_draws_and_labels_the_stalled_car(tmp_path: Path) -> None:
    """``hcomc simulate`` of a corridor with trajectories, then its replay: the stalled car
    has a size (it is drawn) and the role STALLED over the whole run."""
    from hcomc.metrics.corridor.record import read_corridor_run
    from hcomc.viz.replay.corridor_run import _fleet, corridor_run_json

    road = tmp_path / "short.toml"
    road.write_text('base = "corridor"\n[corridor]\nduration = 60.0\n[[faults]]\n'
                    'kind = "stalled_vehicle"\nposition = 120.0\n', encoding="utf-8")  # fmt: skip
    out = tmp_path / "run"
    result = runner.invoke(app, ["simulate", str(road), "--trajectory-interval", "1",
                                 "--out", str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    record = read_corridor_run(out)
    i = len(record.trips)  # after every trip
    page = corridor_run_json(record, "stalled")
    roles = page["roles"]
    (k,) = [k for k, v in enumerate(roles["vehicle"]) if v == i]
    assert roles["names"][roles["role"][k]] == "STALLED"
    kind, length, width = _fleet(record, page["vehicles"])
    assert (kind[i], length[i], width[i]) == (Kind.HDV, 5.0, 1.8)  # the engine's car


def test_falsify_moves_the_stalled_car_along_the_lane() -> None:
    """A search from the stalled car with ``faults.0.position`` in its box: every evaluated
    run has the car where the search put it, and the worst case's config runs again to the
    same least TTC."""
    from hcomc.robustness.falsify import FalsifySpec, evaluate, falsify

    spec = FalsifySpec(condition="C2", controller="fifo", faults=("stalled",),
                       space={"faults.0.position": (30.0, 240.0), "seed": (0, 50)},
                       overrides={"duration": 60.0})  # fmt: skip
    found = falsify(spec, 6, search_seed=1)
    assert len(found) == 6
    for case in found:
        (fault,) = case.config.faults
        assert fault.kind == "stalled_vehicle"
        assert fault.position == pytest.approx(case.values["faults.0.position"])
        assert 30.0 <= fault.position <= 240.0
    worst = min(found, key=lambda c: c.least_ttc)
    again = evaluate(spec, {**worst.values, "seed": float(worst.seed)})
    assert again.least_ttc == worst.least_ttc


@pytest.mark.parametrize("controller", ["fifo", "hcomc"])
def test_at_the_least_position_the_ramp_vehicles_still_merge(controller: str) -> None:
    """The least position allowed (24 m among 5 m cars: its length 5, 3 x 5 to steer around
    it, MOBIL's min_gap 2, the jam distance s0 2) leaves a place to merge before the car:
    VR merges, nobody collides."""
    config = load_config("C2", control={"controller": controller},
                         faults=[{"kind": "stalled_vehicle", "position": 24.0}])  # fmt: skip
    sim = _run(config)
    assert sim.key_group is not None
    assert sim.key_group.vr in sim.log.events_of(EventKind.MERGE)["vehicle"].tolist()
    assert sim.log.events_of(EventKind.COLLISION).size == 0


def _stalled_page(tmp_path: Path) -> tuple[Path, Simulation]:
    from hcomc.viz.replay import write_replay

    sim = _run(_config("fifo", duration=40.0))
    return write_replay(tmp_path / "stalled.html", [sim.log], titles=["stalled"]), sim


def test_the_replay_labels_the_stalled_car(tmp_path: Path) -> None:
    """The replay's roles give the stalled car the role STALLED over the whole run, beside
    the key roles."""
    from hcomc.viz.replay.decisions import ROLE_NAMES, decisions_json

    page, sim = _stalled_page(tmp_path)
    (i,) = sim.stalled.tolist()
    roles = decisions_json(sim.log, sim.config.road.lane_width)["roles"]
    assert roles["names"] == list(ROLE_NAMES)
    mine = [k for k, v in enumerate(roles["vehicle"]) if v == i]
    assert [roles["names"][roles["role"][k]] for k in mine] == ["STALLED"]
    (k,) = mine
    assert roles["t0"][k] == float(sim.log.t[0])
    assert roles["t1"][k] == float(sim.log.t[sim.log.n_recorded - 1])
    assert '"STALLED"' in page.read_text(encoding="utf-8")


@pytest.mark.skipif(find_chromium() is None, reason="chromium is not installed (CI installs "
                    "Debian's package in .ci/run)")  # fmt: skip
def test_the_replay_panel_says_what_the_stalled_car_is(tmp_path: Path) -> None:
    """In Chromium: hovering the stalled car names it, mid-run."""
    page, sim = _stalled_page(tmp_path)
    (i,) = sim.stalled.tolist()
    with Chromium(1280, 900) as chrome:
        chrome.open(page.resolve().as_uri())
        assert chrome.evaluate("window.hcomcReplay && hcomcReplay.ready") is True
        chrome.evaluate(f"hcomcReplay.seek({float(sim.log.t[200])!r})")
        text = chrome.evaluate(f"hcomcReplay.hover({i}, 0)")
        assert "role STALLED (a broken-down car no controller plans for)" in text
        assert chrome.console_errors == []
