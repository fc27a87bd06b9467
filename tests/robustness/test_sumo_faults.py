"""The channel, faults and shield in the SUMO co-simulation: nominal settings give the
co-simulation's run, the faults act as they say, and a campaign runs with --engine sumo."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import ScenarioConfig, load_config
from hcomc.config.impairment_tables import ChannelParams, FaultParams, ShieldParams
from hcomc.experiments.runner import configuration_overrides
from hcomc.sim.log import EventKind

pytest.importorskip("libsumo")

runner = CliRunner()
WINDOW = {"delay_min": 1.0, "delay_max": 1.0, "duration_min": 2.0, "duration_max": 2.0}


def _config(condition: str = "C1") -> ScenarioConfig:
    return load_config(condition, **configuration_overrides("HCOMC", {}), duration=50.0)


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))


def _faulted(config: ScenarioConfig, seed: int, **settings):
    """A co-simulation with the impairments of ``settings`` (channel, fault, shield)."""
    from hcomc.robustness.impairments import Impairments
    from hcomc.sumo.cosim import SumoSimulation

    impaired = Impairments(**settings)
    return SumoSimulation(config, seed, listeners=[impaired]), impaired


def test_nominal_settings_give_the_cosimulation_bit_for_bit():
    from hcomc.sumo.cosim import SumoSimulation

    config = _config()
    nominal = SumoSimulation(config, 0).run()
    faulted = _faulted(config, 0)[0].run()
    for name in ("x", "v", "a", "lane", "active"):
        assert _same(getattr(faulted, name), getattr(nominal, name)), name
    assert len(faulted.meta["plans"]) == len(nominal.meta["plans"]) > 0


def test_emergency_braking_in_sumo_at_a_merg_then_sumo_drives_again():
    fault = FaultParams(kind="emergency_brake", role="vmf", **WINDOW)
    sim, impaired = _faulted(_config(), 0, faults=[fault])
    log = sim.run()
    f = impaired.fault
    (vmf,) = f.vehicles
    assert vmf == sim.key_group.vmf
    t = log.t
    # SUMO reports the acceleration of the step that ended at t: from the first step after
    # the start to the window's end
    during = (t > f.start + 0.15) & (t < f.end - 0.05) & (log.v[:, vmf] > 0)
    assert during.sum() >= 15
    a_merg = sim.config.control.safety_emergency_decel
    np.testing.assert_allclose(log.a[during, vmf], -a_merg, atol=1e-6)
    after = (t > f.end + 0.5) & log.active[:, vmf]
    assert after.any()
    assert np.all(log.a[after, vmf] > -a_merg + 1e-3)


def test_a_lossy_channel_and_the_shield_act_in_sumo():
    lossy = ChannelParams(latency=0.3, loss=0.7, loss_model="gilbert_elliott")
    sim, impaired = _faulted(_config(), 2, channel=lossy, shield=ShieldParams(enabled=True))
    log = sim.run()
    assert impaired.plans_lost > 0
    assert len(sim.decisions) > impaired.plans_lost  # a lost plan is made again
    assert impaired.channel.received < impaired.channel.broadcasts
    assert impaired.shield.overrides
    for o in impaired.shield.overrides:
        step = round((o.t + sim.config.warmup) / sim.dt)
        if o.action == "hold_change":  # a ramp vehicle's commanded merge waits
            assert o.vehicle in sim.key_groups
        else:  # a commanded vehicle brakes at least b_min in the next step
            assert o.action == "brake"
            assert o.vehicle in impaired.commanded_at[step]
            row = int(np.argmin(np.abs(log.t - (o.t + sim.dt))))
            assert log.a[row, o.vehicle] <= -impaired.shield.params.brake_min + 1e-6


def test_campaign_in_sumo_through_the_cli(tmp_path):
    out = tmp_path / "sumo"
    args = ["faults", "--engine", "sumo", "--seeds", "2", "--conditions", "C3",
            "--configurations", "HCOMC", "--faults", "none,brake-vmf", "--channels", "ideal",
            "--workers", "1", "--out", str(out)]  # fmt: skip
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    runs = pd.read_csv(out / "runs.csv")
    assert len(runs) == 2 * 2 * 2  # faults x shield x seeds
    meta = json.loads((out / "campaign.json").read_text())
    assert meta["spec"]["engine"] == "sumo"
    assert meta["sumo_version"]
    # its runs are the co-simulation's: the nominal row's merge time is SUMO's
    from hcomc.metrics import key_window
    from hcomc.metrics.outcome import merge_outcome
    from hcomc.sumo.cosim import SumoSimulation

    config = load_config("C3", **configuration_overrides("HCOMC", {}))
    merged = 0
    for seed in (0, 1):  # a run without a merge has no merge time in either
        log = SumoSimulation(config, seed).run()
        nominal = runs[(runs["fault"] == "none") & ~runs["shield"] & (runs["seed"] == seed)]
        outcome = merge_outcome(log, key_window(log))
        assert nominal.iloc[0]["merge_time"] == pytest.approx(outcome.merge_time, nan_ok=True)
        merged += int(outcome.merge_time == outcome.merge_time)
    assert merged >= 1


def test_the_config_tables_run_in_sumo_as_the_python_listener():
    """``--engine sumo`` with [v2x], [[faults]] and [shield] in the config: the co-simulation
    made by the experiments' factory carries them, the same run as the listener by hand."""
    from hcomc.experiments.runner import make_simulation
    from hcomc.robustness.impairments import Impairments

    tables = {"faults": [{"kind": "emergency_brake", **WINDOW}],
              "v2x": {"latency": 0.1, "loss": 0.1}, "shield": {"enabled": True}}  # fmt: skip
    by_config = make_simulation(load_config("C1", **configuration_overrides("HCOMC", {}),
                                            duration=50.0, **tables), 0, "sumo")  # fmt: skip
    (listener,) = by_config.listeners
    assert isinstance(listener, Impairments)
    log = by_config.run()
    sim, by_hand = _faulted(_config(), 0, channel=ChannelParams(latency=0.1, loss=0.1),
                            faults=[FaultParams(kind="emergency_brake", **WINDOW)],
                            shield=ShieldParams(enabled=True))  # fmt: skip
    plain = sim.run()
    for name in ("x", "v", "a", "lane", "active"):
        assert _same(getattr(log, name), getattr(plain, name)), name
    assert listener.summary() == by_hand.summary()
    assert log.events_of(EventKind.FAULT)["vehicle"].tolist() == [sim.key_group.vmf]


def test_a_stalled_vehicle_stands_in_sumo_where_our_engine_puts_it():
    """The stalled car is added to SUMO before its first step at x = 800 m on the
    acceleration lane: it stands there all run at speed 0, is nobody's VR, logs no
    insertion, and no ramp vehicle passes it in its lane or runs into it."""
    from hcomc.robustness.impairments import listeners_of
    from hcomc.sumo.cosim import SumoSimulation

    config = load_config("C2", **configuration_overrides("FIFO", {}), duration=60.0,
                         faults=["stalled"])  # fmt: skip
    sim = SumoSimulation(config, 1, listeners=listeners_of(config))
    log = sim.run()
    (i,) = sim.stalled.tolist()
    assert log.meta["stalled"] == [i]
    np.testing.assert_array_equal(log.x[:, i], 800.0)
    np.testing.assert_array_equal(log.v[:, i], 0.0)
    assert i not in sim.key_groups
    assert i not in log.events_of(EventKind.INSERTION)["vehicle"].tolist()
    assert log.events_of(EventKind.FAULT)["vehicle"].tolist() == [i]
    assert log.events_of(EventKind.COLLISION).size == 0
    others = (log.lane == 0) & log.active & (np.arange(log.x.shape[1]) != i)
    assert others.any()
    assert np.all(log.x[others] < 800.0 - config.road.vehicle_length)


def test_hcomc_run_measures_a_stalled_run_in_sumo():
    """``hcomc run --engine sumo`` with the stalled car: the paper's metrics against its
    own undisturbed SUMO run (the same vehicle columns), the fault in the row."""
    result = runner.invoke(app, [
        "run", "C2", "--controller", "fifo", "--seeds", "1", "--engine", "sumo", "--workers",
        "1", "--set", 'faults=["stalled"]', "--set", "duration=60", "--json",
    ])  # fmt: skip
    assert result.exit_code == 0, result.output
    (row,) = json.loads(result.output.strip().splitlines()[-1])
    assert row["fault_kinds"] == "stalled_vehicle"
