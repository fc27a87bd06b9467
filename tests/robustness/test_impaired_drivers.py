"""Sensor noise and distracted drivers, checked against their car following recomputed from
the run's own log: the acceleration a faulty vehicle drives with in the window equals Eq. 1
(or Eq. 3) evaluated on what the fault says it perceives."""

from __future__ import annotations

import math

import numpy as np

from hcomc.config import ScenarioConfig, load_config
from hcomc.config.impairment_tables import FaultParams
from hcomc.equations.car_following import follow_accel
from hcomc.experiments.runner import configuration_overrides
from hcomc.road import Kind
from hcomc.robustness.faults import Fault
from hcomc.robustness.impairments import Impairments
from hcomc.sim.engine import Simulation
from hcomc.sim.log import SimulationLog

WINDOW = {"delay_min": 1.0, "delay_max": 1.0, "duration_min": 3.0, "duration_max": 3.0}


def _config(condition: str) -> ScenarioConfig:
    return load_config(condition, **configuration_overrides("HCOMC", {}))


def _expected(log: SimulationLog, config: ScenarioConfig, i: int, row: int, seen: int) -> float:
    """Vehicle ``i``'s car following in ``row``'s lane on the state of log row ``seen``
    (leader: the nearest vehicle ahead in that lane then), with its kind's parameters."""
    lane = log.lane[row, i]
    x = log.x[seen].astype(float)
    there = np.flatnonzero(log.active[seen] & (log.lane[seen] == lane) & (x > x[i]))
    v = float(log.v[seen, i])
    if there.size:
        j = there[np.argmin(x[there])]
        s, vl, al = x[j] - config.road.vehicle_length - x[i], log.v[seen, j], log.a[seen, j]
    else:
        s, vl, al = math.inf, v, 0.0
    cav = bool(log.kind[i] == Kind.CAV)
    p = config.cav if cav else config.hdv
    c = config.cav.coolness if cav else 0.0
    model = (p.desired_speed, p.time_headway, p.min_gap, p.max_accel, p.comfort_decel, p.exponent)
    return float(follow_accel(float(s), v, float(vl), float(al), *model, c, p.variant == "iidm"))


def _window_rows(log: SimulationLog, sim: Simulation, acting: Fault, i: int) -> np.ndarray:
    t = log.t
    a_merg = sim.config.control.safety_emergency_decel
    rows = (t > acting.start + 0.05) & (t < acting.end - 0.05) & (log.v[:, i] > 0)
    return np.flatnonzero(rows & (log.a[:, i] > -a_merg + 1e-3))


def _faulted_log(config: ScenarioConfig, seed: int, fault: FaultParams) -> SimulationLog:
    return Simulation(config, seed, listeners=[Impairments(faults=[fault])]).run()


def _first_faulted(condition: str, fault: FaultParams) -> tuple[Simulation, Fault, SimulationLog]:
    """The first run of seeds 0-5 whose fault found its vehicles, that fault and the log."""
    for seed in range(6):
        impaired = Impairments(faults=[fault])
        sim = Simulation(_config(condition), seed, listeners=[impaired])
        log = sim.run()
        if impaired.fault.vehicles:
            return sim, impaired.fault, log
    raise AssertionError(f"no vehicle for {fault.kind} in seeds 0-5")


def test_distracted_drivers_act_on_the_traffic_of_two_seconds_ago():
    fault = FaultParams(kind="distracted_hdv", distracted_gap_error=0.0, **WINDOW)
    sim, acting, log = _first_faulted("C5", fault)
    lag = round(fault.distracted_delay / sim.dt)
    assert len(acting.vehicles) >= 2
    for i in acting.vehicles:
        rows = _window_rows(log, sim, acting, i)
        assert rows.size >= 20
        # a command computed before the step from row k - 1 is logged in row k
        got = log.a[rows, i]
        want = [_expected(log, sim.config, i, k - 1, k - 1 - lag) for k in rows]
        np.testing.assert_allclose(got, want, atol=1e-5)
        now = [_expected(log, sim.config, i, k - 1, k - 1) for k in rows]
        assert np.max(np.abs(np.asarray(now) - got)) > 1e-3  # not the present traffic


def test_distracted_gap_errors_change_only_the_window():
    exact = FaultParams(kind="distracted_hdv", distracted_gap_error=0.0, **WINDOW)
    noisy = exact.model_copy(update={"distracted_gap_error": 0.2})
    sim, acting, log = _first_faulted("C5", noisy)
    log0 = _faulted_log(sim.config, sim.seed, exact)
    before = log.t < acting.start - 1e-9
    np.testing.assert_array_equal(log.x[before], log0.x[before])
    # a driver with a leader misjudges its gap (one on a free road has no gap to misjudge)
    changed = [
        np.max(np.abs(log.a[rows, i] - log0.a[rows, i]))
        for i in acting.vehicles
        if (rows := _window_rows(log, sim, acting, i)).size
    ]
    assert max(changed) > 1e-3


def test_a_cav_with_exact_sensors_drives_by_its_own_car_following():
    fault = FaultParams(kind="sensor_noise", role="vmc", gap_noise=0.0, speed_noise=0.0,
                        **WINDOW)  # fmt: skip
    sim, acting, log = _first_faulted("C1", fault)
    (i,) = acting.vehicles
    assert i == sim.key_group.vmc
    rows = _window_rows(log, sim, acting, i)
    assert rows.size >= 20
    want = [_expected(log, sim.config, i, k - 1, k - 1) for k in rows]
    np.testing.assert_allclose(log.a[rows, i], want, atol=1e-5)


def test_sensor_noise_perturbs_the_window_and_nothing_before_it():
    fault = FaultParams(kind="sensor_noise", role="vmc", **WINDOW)
    sim, acting, log = _first_faulted("C1", fault)
    nominal = Simulation(sim.config, sim.seed).run()
    before = log.t < acting.start - 1e-9
    np.testing.assert_array_equal(log.a[before], nominal.a[before])
    (i,) = acting.vehicles
    rows = _window_rows(log, sim, acting, i)
    exact = np.array([_expected(log, sim.config, i, k - 1, k - 1) for k in rows])
    residual = log.a[rows, i] - exact
    assert np.mean(np.abs(residual) > 1e-5) > 0.9  # every step measures anew
    same = _faulted_log(sim.config, sim.seed, fault)
    np.testing.assert_array_equal(same.a, log.a)  # seeded
