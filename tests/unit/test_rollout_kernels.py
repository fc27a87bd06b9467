"""The compiled scalar forms inside the HCOMC rollout equal the vectorised model kernels."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.config import load_config
from hcomc.control.hcomc.rollout import accel, psi, quintic
from hcomc.models.quintic import quintic_shape
from hcomc.models.transition import transition_weight
from hcomc.road import Kind
from hcomc.sim.fleet import Fleet, follow

FLEET = Fleet.build(load_config("C1"), np.array([Kind.HDV, Kind.CAV]), np.zeros(2, dtype=bool))


def _params(i: int) -> np.ndarray:
    f = FLEET
    return np.array([f.v0[i], f.T[i], f.s0[i], f.a[i], f.b[i], f.delta[i], f.coolness[i],
                     f.length[i], f.width[i]])  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(
    kind=st.sampled_from([0, 1]),
    s=st.one_of(st.floats(0.0, 300.0), st.just(np.inf)),
    v=st.floats(0.0, 40.0),
    vl=st.floats(0.0, 40.0),
    al=st.floats(-8.0, 3.0),
)
def test_scalar_accel_equals_fleet_follow(kind, s, v, vl, al):
    expected = follow(FLEET, np.array([kind]), np.array([s]), np.array([v]), np.array([vl]),
                      np.array([al]))[0]  # fmt: skip
    assert accel(_params(kind), s, v, vl, al) == pytest.approx(expected, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("duration", [3.0, 4.0, 6.0])
def test_scalar_transition_equals_eq14_kernel(duration):
    gamma = np.arctanh(1.0 - 2.0 * 0.01)
    for tau in np.linspace(-1.0, duration + 1.0, 41):
        assert psi(tau, duration, gamma) == pytest.approx(
            float(transition_weight(tau, duration, 0.01)), abs=1e-12
        )


def test_scalar_quintic_equals_kernel():
    for xi in np.linspace(-0.2, 1.2, 71):
        p, dp, _ = quintic_shape(xi)
        q, dq = quintic(xi)
        assert q == pytest.approx(float(p), abs=1e-12)
        assert dq == pytest.approx(float(dp), abs=1e-12)
