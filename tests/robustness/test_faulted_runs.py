"""Runs under a V2X channel, injected faults and the shield, checked against the nominal
engine and against what each setting says it does."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.config.impairment_tables import ChannelParams, FaultParams, ShieldParams
from hcomc.experiments.runner import configuration_overrides
from hcomc.interface.listener import StepListener
from hcomc.robustness.impairments import Impairments
from hcomc.robustness.shield import rss_safe_distance
from hcomc.sim.engine import Simulation
from hcomc.sim.step.plans import P_VMC, P_VMC_CMD


def _config(condition="C1", configuration="HCOMC"):
    return load_config(condition, **configuration_overrides(configuration, {}))


def _faulted(config, seed, *others, **settings) -> tuple[Simulation, Impairments]:
    """A run of our engine with the impairments of ``settings`` (channel, fault, shield),
    after the listeners ``others``."""
    impaired = Impairments(**settings)
    return Simulation(config, seed, listeners=[*others, impaired]), impaired


@pytest.mark.parametrize(("condition", "configuration", "seed"),
                         [("C1", "HCOMC", 0), ("C3", "FIFO", 1), ("C5", "Game", 2)])  # fmt: skip
def test_nominal_settings_give_the_nominal_run_bit_for_bit(condition, configuration, seed):
    config = _config(condition, configuration)
    nominal = Simulation(config, seed).run()
    faulted = _faulted(config, seed)[0].run()
    for name in ("x", "v", "a", "lane", "active"):
        np.testing.assert_array_equal(getattr(faulted, name), getattr(nominal, name), name)
    for field in ("t", "kind", "vehicle", "other", "x", "value"):
        np.testing.assert_array_equal(faulted.events[field], nominal.events[field], field)


def test_stale_view_is_the_state_one_latency_ago():
    history: dict[int, np.ndarray] = {}

    class Remember(StepListener):
        def before_step(self, run, t):
            history[run.step_index] = run.x.copy()

    sim, _ = _faulted(_config(), 0, Remember(), channel=ChannelParams(latency=0.3))
    seen: list = []
    controller = sim.controller

    class Spy:
        name = "spy"

        def plan(self, view, group, rng):
            seen.append((view, sim.active.copy()))
            return controller.plan(view, group, rng)

    sim.controller = Spy()
    sim.run()
    assert seen, "no decision"
    for view, on_road in seen:
        # broadcasts every 0.1 s from t = 0; a state arrives 0.3 s after it was sent (a
        # vehicle that left the road is remembered for max_age = 2 s)
        assert np.all(view.age[view.active] <= 2.0 + 1e-9)
        heard = np.isfinite(view.age) & on_road
        assert heard.any()
        age = view.age[heard]
        assert np.all((age >= 0.3 - 1e-9) & (age < 0.4 + 1e-9)), age
        sent_step = round((view.t - float(age[0]) + sim.config.warmup) / sim.dt)
        np.testing.assert_array_equal(view.x[heard], history[sent_step][heard])


def test_plans_arrive_one_latency_late_or_never():
    late, late_channel = _faulted(_config(), 0, channel=ChannelParams(latency=0.5))
    late.run()
    ideal, _ = _faulted(_config(), 0)
    ideal.run()
    assert late.decisions
    assert late_channel.plans_lost == 0
    # the first plan is made at VR's entry in both runs, executed 0.5 s later in one
    assert late.decisions[0].t0 == ideal.decisions[0].t0
    lossy, channel = _faulted(_config(), 0, channel=ChannelParams(loss=0.9))
    lossy.run()
    assert channel.plans_lost > 0
    assert channel.plans_lost < len(lossy.decisions)


def test_emergency_braking_of_vmf_at_a_merg():
    fault = FaultParams(kind="emergency_brake", role="vmf", delay_min=2, delay_max=2,
                        duration_min=1.5, duration_max=1.5)  # fmt: skip
    sim, impaired = _faulted(_config(), 0, faults=[fault])
    log = sim.run()
    vmf = sim.key_group.vmf
    f = impaired.fault
    assert f.vehicle == vmf >= 0
    t = log.t
    during = (t > f.start + 0.05) & (t < f.end - 0.05) & (log.v[:, vmf] > 0)
    assert during.sum() >= 10
    a_merg = sim.config.control.safety_emergency_decel
    np.testing.assert_allclose(log.a[during, vmf], -a_merg, atol=1e-4)
    after = (t > f.end + 0.5) & log.active[:, vmf]
    assert np.all(log.a[after, vmf] > -a_merg + 1e-3)


def test_aggressive_hdvs_drive_short_headways_the_controller_does_not_know():
    fault = FaultParams(kind="aggressive_hdv")
    for seed in range(6):
        sim, impaired = _faulted(_config("C3"), seed, faults=[fault])
        sim.run()
        if impaired.fault.vehicle >= 0:
            break
    else:
        raise AssertionError("no human-driven key vehicle in seeds 0-5")
    i = impaired.fault.vehicle
    assert sim.driving.T[i] == sim.arrays.matrix[1, i] == fault.time_headway
    assert sim.fleet.T[i] == sim.config.hdv.time_headway
    assert sim.requests[0][0].fleet.T[i] == sim.config.hdv.time_headway


def test_a_cav_that_ignores_its_command_is_not_commanded():
    for seed in range(10):
        sim, impaired = _faulted(_config(), seed, faults=[FaultParams(kind="ignore_command")])
        sim.run_to(sim.n_warmup)
        while not sim.decisions and sim.step_index < sim.n_warmup + sim.n_steps:
            sim.step()
        plan = sim.decisions[0] if sim.decisions else None
        if plan is not None and plan.cooperating >= 0:
            break
    else:
        raise AssertionError("no cooperating plan in seeds 0-9")
    rows = sim.arrays.plan_int[: int(sim.arrays.counters[7])]
    mine = rows[rows[:, P_VMC] == plan.cooperating]
    assert mine.size
    assert np.all(mine[:, P_VMC_CMD] == 0)
    assert impaired.fault.vehicle == plan.cooperating


def test_shield_keeps_commanded_vehicles_at_rss_distance_or_braking():
    """With the shield, every step a commanded vehicle is closer than the RSS distance to a
    vehicle ahead in its lane is a step the shield commands it to brake."""
    fault = FaultParams(kind="emergency_brake", role="vmf")
    params = ShieldParams(enabled=True)
    total = 0
    for seed in range(4):
        sim, impaired = _faulted(_config(), seed, faults=[fault], shield=params)
        log = sim.run()
        brakes = [o for o in impaired.shield.overrides if o.action == "brake"]
        total += len(impaired.shield.overrides)
        step_of = {round((o.t + sim.config.warmup) / sim.dt): o.vehicle for o in brakes}
        for step, vehicle in step_of.items():
            assert vehicle in impaired.commanded_at.get(step, frozenset())
        assert impaired.collisions_commanded(log) == 0
    assert total > 0
    # the defaults' distance at 90 km/h behind a vehicle as fast (docs/robustness.md):
    # 25 * 0.3 + 1.4 * 0.3^2 / 2 + (25 + 0.3 * 1.4)^2 / (2 * 4) - 25^2 / (2 * 7.5)
    d = rss_safe_distance(25.0, 25.0, params.response_time, params.accel_max,
                          params.brake_min, params.brake_max)  # fmt: skip
    assert float(d) == pytest.approx(7.5 + 0.063 + 25.42**2 / 8 - 625 / 15, abs=1e-9)


def test_sensor_dropout_holds_the_acceleration_of_its_start():
    fault = FaultParams(kind="sensor_dropout", role="vmc", delay_min=1, delay_max=1,
                        duration_min=2, duration_max=2)  # fmt: skip
    for seed in range(6):
        sim, impaired = _faulted(_config(), seed, faults=[fault])
        log = sim.run()
        if impaired.fault.vehicle >= 0:
            break
    else:
        raise AssertionError("no CAV VMC in seeds 0-5")
    f = impaired.fault
    vmc = f.vehicle
    assert vmc == sim.key_group.vmc
    t = log.t
    during = (t > f.start + 0.05) & (t < f.end - 0.05) & (log.v[:, vmc] > 0)
    assert during.sum() >= 15
    held = log.a[during, vmc]
    np.testing.assert_allclose(held, held[0], atol=1e-5)
