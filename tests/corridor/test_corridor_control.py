"""Merge control on a corridor (the engine's plans at every on-ramp, measured by
hcomc.metrics.corridor.events): merge events whose key vehicles and surrogate safety agree with
an independent computation on the full trajectories, commanded merges that keep to their
plan, determinism, and the command line."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.control.longitudinal_candidate import MERGE_OFFSET
from hcomc.corridor import Corridor, corridor_to_toml
from hcomc.metrics.corridor import simulate_corridor
from hcomc.safety.surrogate import CLOSING_SPEED

CAR = {"length": 5.0, "desired_speed": 30.0, "max_speed": 50.0, "cav": {}}


def busy_ramp(
    controller: str = "none", lanes: int = 2, replan_period: float = 0.0, **run: Any
) -> Corridor:
    """Two lanes, one on-ramp at 1000 m, dense mainline and ramp demand, half CAVs."""
    return Corridor.model_validate({
        "corridor": {"duration": 200.0, "seed": 3, **run},
        "road": {"lanes": lanes, "length": 2500.0,
                 "on_ramps": [{"id": "on1", "x": 1000.0, "accel_length": 250.0,
                               "control_zone_length": 300.0, "ramp_length": 450.0}]},
        "demand": {"main": {"flow": 2600.0, "cav_share": 0.5, "classes": {"car": 1.0}},
                   "on1": {"flow": 700.0, "cav_share": 0.5, "classes": {"car": 1.0}}},
        "vehicles": {"car": CAR},
        "detectors": {"spacing": 0.0, "around_ramps": False},
        "control": {"controller": controller, "replan_period": replan_period},
    })  # fmt: skip


@pytest.fixture(scope="module")
def uncontrolled() -> Any:
    """The busy ramp without a controller, every vehicle sampled at every step (its logged
    lane: the one it drives in, the target of a lane change once it has crossed the line)."""
    c = busy_ramp()
    run = simulate_corridor(c, trajectory_interval=c.corridor.step_length)
    return run, run.trajectories


def _at(traj: pd.DataFrame, t: float) -> pd.DataFrame:
    return traj[np.isclose(traj.t, t)]


def test_every_vr_entering_the_zone_is_an_event_with_the_key_vehicles_of_section_2a(
    uncontrolled: Any,
):
    (run, traj), zone = uncontrolled, 1000.0 - 300.0
    merges = run.merges
    ramp = run.trips[run.trips.origin == "on1"]
    reached = ramp[ramp["insert"].notna()]
    assert len(merges) > 20
    assert set(merges.vr) <= set(reached.id)
    inserted = run.trips.set_index("id")["insert"]
    for ev in merges.itertuples():
        now = _at(traj, ev.zone_time)
        now = now[inserted.loc[now.id].to_numpy() < ev.zone_time - 1e-9]  # as identified
        me = now[now.id == ev.vr].iloc[0]
        before = _at(traj, ev.zone_time - 0.1)
        assert me.x >= zone
        assert me.lane == -1
        assert before[before.id == ev.vr].x.iloc[0] < zone  # it had just entered it
        lane0, lane1 = now[now.lane == 0], now[now.lane == 1]
        ahead, behind = lane0[lane0.x > me.x], lane0[lane0.x <= me.x]
        vmf = ahead.loc[ahead.x.idxmin(), "id"] if len(ahead) else -1
        vmc = behind.loc[behind.x.idxmax(), "id"] if len(behind) else -1
        assert (ev.vmf, ev.vmc) == (vmf, vmc)
        if vmc < 0:
            continue
        x_vmc = behind.x.max()
        rear = lane0[lane0.x < x_vmc]
        assert ev.vmr == (rear.loc[rear.x.idxmax(), "id"] if len(rear) else -1)
        front, back = lane1[lane1.x > x_vmc], lane1[lane1.x <= x_vmc]
        assert ev.vnf == (front.loc[front.x.idxmin(), "id"] if len(front) else -1)
        assert ev.vnr == (back.loc[back.x.idxmax(), "id"] if len(back) else -1)


def _least_ttc(traj: pd.DataFrame, ids: list[int], t0: float, t1: float) -> tuple[float, float]:
    """Least TTC and largest DRAC of ``ids`` against their lane leaders over [t0, t1]."""
    window = traj[(traj.t > t0 - 1e-9) & (traj.t < t1 + 1e-9)]
    ttc, drac = np.inf, 0.0
    for _, now in window.groupby("t"):
        for i in ids:
            me = now[now.id == i]
            if me.empty:
                continue
            me = me.iloc[0]
            ahead = now[(now.code == me.code) & (now.x > me.x)]
            if ahead.empty:
                continue
            lead = ahead.loc[ahead.x.idxmin()]
            closing = me.v - lead.v
            if closing < CLOSING_SPEED:
                continue
            gap = lead.x - 5.0 - me.x
            ttc = min(ttc, max(gap, 0.0) / closing)
            drac = max(drac, closing**2 / (2 * max(gap, 1e-3)))
    return ttc, drac


def test_surrogate_safety_of_an_event_is_that_of_its_key_vehicles_over_its_window(
    uncontrolled: Any,
):
    run, traj = uncontrolled
    merges = run.merges
    window = run.corridor.merges.window_after
    checked = 0
    for ev in merges[merges.merged].head(6).itertuples():
        ids = [int(i) for i in (ev.vr, ev.vmc, ev.vmr, ev.vnr) if i >= 0]
        ttc, drac = _least_ttc(traj, ids, ev.zone_time, ev.merge_time + window)
        assert ev.min_ttc == pytest.approx(ttc, rel=1e-5)  # the log's float32 speeds
        assert ev.max_drac == pytest.approx(drac, rel=1e-5, abs=1e-9)
        checked += np.isfinite(ttc)
    assert checked >= 3  # some events had a closing vehicle: the comparison was not vacuous


def test_without_a_controller_nothing_is_planned_and_merged_matches_the_trips(uncontrolled: Any):
    run, _ = uncontrolled
    assert run.decisions == 0
    assert run.merges.plans.eq(0).all()
    trips = run.trips.set_index("id")
    assert (run.merges.merged.to_numpy() == trips.loc[run.merges.vr, "merge_time"].notna()).all()
    summary = run.summary()["on_ramps"]["on1"]["merge_events"]
    assert summary["events"] == len(run.merges)
    assert summary["merged_share"] == pytest.approx(run.merges.merged.mean())


@pytest.fixture(scope="module")
def with_fifo() -> Any:
    """The busy ramp with FIFO replanning every second (FIFO-R)."""
    return simulate_corridor(busy_ramp("fifo", replan_period=1.0))


def test_commanded_vrs_merge_from_their_plans_merge_position(with_fifo: Any):
    run = with_fifo
    assert run.collision_count == 0
    m = run.merges
    commanded = m[m.cav & m.merged & (m.plans > 0) & ~m.fallback]
    assert len(commanded) > 3
    # FIFO starts a CAV VR's change MERGE_OFFSET into the acceleration lane; it ends further on
    assert (commanded.merge_position >= MERGE_OFFSET).all()
    assert m.plans.sum() == run.decisions


def test_a_controlled_corridor_run_is_deterministic():
    first, again = (simulate_corridor(busy_ramp("fifo"), duration=120.0) for _ in range(2))
    assert first.decisions > 0
    pd.testing.assert_frame_equal(first.merges.drop(columns="decision_ms"),
                                  again.merges.drop(columns="decision_ms"))  # fmt: skip
    pd.testing.assert_frame_equal(first.trips, again.trips)


def test_simulate_corridor_with_a_controller_on_the_command_line(tmp_path):
    path = tmp_path / "ramp.toml"
    path.write_text(corridor_to_toml(busy_ramp(lanes=3)), encoding="utf-8")  # not the paper's
    out = tmp_path / "run"
    args = ["simulate", str(path), "--controller", "fifo", "--duration", "90", "--json",
            "--out", str(out)]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout.strip().splitlines()[-1])
    assert summary["controller"] == "fifo"
    assert summary["decisions"] > 0
    events = summary["on_ramps"]["on1"]["merge_events"]
    merges = pd.read_csv(out / "merges.csv")
    assert events["events"] == len(merges)
    assert events["plans"] == merges.plans.sum()
    assert "Merges" in (out / "corridor.html").read_text(encoding="utf-8")
    assert json.loads((out / "manifest.json").read_text())["controller"] == "fifo"


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--controller", "nope"], "option '--controller' = 'nope'"),
        (["--controller", "fifo", "--optimizer", "pso"], "option '--optimizer' = 'pso'"),
    ],
)
def test_bad_controller_options_on_a_corridor_are_one_line_errors(args, needle):
    result = CliRunner().invoke(app, ["simulate", "corridor", "--duration", "60", *args])
    assert result.exit_code == 2
    assert needle in result.output
    assert "Traceback" not in result.output
