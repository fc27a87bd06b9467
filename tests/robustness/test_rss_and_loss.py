"""The robustness building blocks against closed forms: the RSS distance, the
Gilbert-Elliott loss chain, the settings' rules."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.config import ConfigError
from hcomc.config.impairment_tables import CHANNELS, FaultParams
from hcomc.robustness.campaign import CampaignSpec
from hcomc.robustness.channel import Channel, GilbertElliott
from hcomc.robustness.shield import rss_safe_distance


def test_rss_distance_closed_form():
    # v_r = 20, v_f = 15, rho = 0.5, a = 2, b_min = 4, b_max = 8:
    # 10 + 0.25 + 21^2 / 8 - 15^2 / 16 = 10.25 + 55.125 - 14.0625
    d = rss_safe_distance(20.0, 15.0, 0.5, 2.0, 4.0, 8.0)
    assert float(d) == pytest.approx(10.25 + 55.125 - 14.0625, abs=1e-12)
    # a much faster front vehicle: never negative
    assert float(rss_safe_distance(5.0, 40.0, 0.3, 1.4, 6.0, 7.5)) == 0.0
    # vectorised, broadcasting
    v = np.array([0.0, 10.0, 30.0])
    out = rss_safe_distance(v, v, 0.0, 0.0, 7.5, 7.5)
    np.testing.assert_allclose(out, 0.0, atol=1e-12)


def _min_gap_under_rss(v_r, v_f, rho, a_max, b_min, b_max, gap0):
    """Smallest gap of a rear vehicle that accelerates at a_max for rho, then brakes at
    b_min, behind a front vehicle braking at b_max from t = 0 (exact ballistic steps of
    about 1 ms, rho a whole number of them)."""
    dt = rho / math.ceil(rho / 1e-3) if rho >= 1e-6 else 1e-3
    rho = rho if rho >= 1e-6 else 0.0
    x_r, x_f, t, gap = 0.0, gap0, 0.0, gap0
    while v_r > 0 or v_f > 0:
        a_r = a_max if t < rho - 1e-12 else -b_min
        a_f = -b_max
        for name in ("r", "f"):
            v, a = (v_r, a_r) if name == "r" else (v_f, a_f)
            if v + a * dt < 0:  # stops within the step
                s = -v * v / (2 * a) if a < 0 else 0.0
                v_new = 0.0
            else:
                s, v_new = v * dt + 0.5 * a * dt * dt, v + a * dt
            if name == "r":
                x_r, v_r = x_r + s, v_new
            else:
                x_f, v_f = x_f + s, v_new
        t += dt
        gap = min(gap, x_f - x_r)
    return gap


@settings(max_examples=60, deadline=None)
@given(
    v_r=st.floats(0, 35), v_f=st.floats(0, 35), rho=st.floats(0, 1),
    a_max=st.floats(0, 3), b_min=st.floats(3, 7.5), extra=st.floats(0, 2),
)  # fmt: skip
def test_rss_distance_is_safe_and_tight(v_r, v_f, rho, a_max, b_min, extra):
    """At the RSS distance the proper response never closes the gap below zero (up to the
    integration step); clearly below it, the worst case collides when the rear vehicle is
    the faster one at the end."""
    b_max = min(b_min + extra, 9.0)
    d = float(rss_safe_distance(v_r, v_f, rho, a_max, b_min, b_max))
    assert _min_gap_under_rss(v_r, v_f, rho, a_max, b_min, b_max, d) >= -0.05


def test_gilbert_elliott_stationary_loss_and_bursts():
    rng = np.random.default_rng(1)
    chain = GilbertElliott(200, 0.3, 5.0, rng)
    lost = np.array([chain.lost() for _ in range(2000)])  # (messages, senders)
    assert lost.mean() == pytest.approx(0.3, abs=0.01)
    runs = []
    for column in lost.T:
        edges = np.diff(np.concatenate([[0], column.astype(int), [0]]))
        runs.extend((np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)).tolist())
    assert np.mean(runs) == pytest.approx(5.0, rel=0.05)


def test_independent_loss_has_no_memory():
    chain = GilbertElliott(500, 0.1, 1.0 / 0.9, np.random.default_rng(2))
    lost = np.array([chain.lost() for _ in range(1000)])
    assert lost.mean() == pytest.approx(0.1, abs=0.005)
    after_loss = lost[1:][lost[:-1]].mean()  # P(lost | previous lost) = P(lost)
    assert after_loss == pytest.approx(0.1, abs=0.01)


def test_channel_presets_and_fault_rules():
    assert CHANNELS["ideal"].ideal
    assert not CHANNELS["lat100-loss10"].ideal
    assert CHANNELS["lat300-loss30-bursty"].loss_model == "gilbert_elliott"
    with pytest.raises(ValueError, match="delay_min <= delay_max"):
        FaultParams(kind="emergency_brake", delay_min=5, delay_max=1)
    with pytest.raises(ValueError, match="extra"):
        FaultParams(kind="emergency_brake", speed=3)  # type: ignore[call-arg]
    with pytest.raises(ConfigError, match="fault 'fire'"):
        CampaignSpec(faults=("fire",))
    assert math.isinf(CHANNELS["ideal"].range)


def test_the_roadside_units_hear_within_range_of_any_ramp():
    """A broadcast reaches the controller when its sender is within ``range`` of one of the
    roadside units (one per on-ramp); on a road without on-ramps, of none, while the
    vehicles still hear each other."""
    params = CHANNELS["lat100-loss10"].model_copy(update={"loss": 0.0, "range": 100.0})
    x = np.array([0.0, 950.0, 1500.0, 2900.0, 5000.0])
    state = {"x": x, "active": np.ones(x.size, dtype=bool)}
    for rsu, heard in (([1000.0, 3000.0], [False, True, False, True, False]),
                       ([], [False] * x.size)):  # fmt: skip
        channel = Channel(params, x.size, rsu, seed=0)
        channel.broadcast(0.0, state)
        message = channel._pending[0]
        assert np.isfinite(message.arrive).tolist() == heard
        assert np.isfinite(message.arrive_v2v).all()
