"""The HCOMC prediction kernels call each equation's one home, with the right parameters."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.config import load_config
from hcomc.control.prediction.layout import R_ACC, R_FREE, R_V, R_X
from hcomc.control.prediction.population import (
    C_DT,
    C_EMERGENCY,
    N_CONSTS,
    N_PARAMS,
    N_ROLES,
    P_IIDM,
    VMC,
    VR,
    KeyVehicles,
    counterfactual,
    resolve_starts,
)
from hcomc.control.prediction.scoring import created_pairs_safety
from hcomc.control.prediction.step import follow_role, integrate, new_state
from hcomc.equations.idm import equilibrium_gap
from hcomc.equations.safety import critical_accel, critical_acceleration
from hcomc.interface import Fleet, Ramp, follow
from hcomc.road import Kind

SRC = Path(__file__).resolve().parents[2] / "src" / "hcomc" / "control" / "hcomc"


def _fleet(variant: str) -> Fleet:
    config = load_config("C1", cav={"variant": variant}, hdv={"variant": variant})
    return Fleet.build(config, np.array([Kind.HDV, Kind.CAV]), np.zeros(2, dtype=bool))


FLEETS = {"idm": _fleet("idm"), "iidm": _fleet("iidm")}


def _params(f: Fleet, i: int) -> np.ndarray:
    """A rollout parameter row, laid out as the controller's ``key_state`` builds it."""
    return np.array([f.v0[i], f.T[i], f.s0[i], f.a[i], f.b[i], f.delta[i], f.coolness[i],
                     f.length[i], f.width[i], f.iidm[i]], dtype=np.float64)  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(
    variant=st.sampled_from(["idm", "iidm"]),
    kind=st.sampled_from([0, 1]),
    s=st.one_of(st.floats(0.0, 300.0), st.just(np.inf)),
    v=st.floats(0.0, 40.0),
    vl=st.floats(0.0, 40.0),
    al=st.floats(-8.0, 3.0),
)
def test_role_following_is_the_engines(variant, kind, s, v, vl, al):
    """Bit for bit, behind a leader and (with the free-road term then taken from ``R_FREE``)
    on a free road at the same speed."""
    fleet = FLEETS[variant]
    ks = np.array([kind, kind])
    expected = follow(fleet, ks, np.array([s, np.inf]), np.array([v, v]), np.array([vl, v]),
                      np.array([al, 0.0]))  # fmt: skip
    S = new_state(np.zeros(1), np.array([v]), np.zeros(1), np.ones(1, dtype=np.bool_))
    params = _params(fleet, kind)[None, :]
    assert np.isnan(S[R_FREE, 0])
    assert follow_role(S, params, 0, s, vl, al) == expected[0]
    assert not np.isnan(S[R_FREE, 0])  # taken once for the step
    assert follow_role(S, params, 0, np.inf, v, 0.0) == expected[1]


def test_a_new_speed_clears_the_free_road_term():
    S = new_state(np.zeros(N_ROLES), np.full(N_ROLES, 20.0), np.zeros(N_ROLES),
                  np.ones(N_ROLES, dtype=np.bool_))  # fmt: skip
    params = np.tile(_params(FLEETS["idm"], 0), (N_ROLES, 1))
    first = follow_role(S, params, VR, np.inf, 20.0, 0.0)
    S[R_ACC] = 1.0
    integrate(S, 0.5, 9.0)
    assert np.isnan(S[R_FREE]).all()
    assert follow_role(S, params, VR, np.inf, 20.5, 0.0) < first  # at the new speed


def test_parameter_rows_carry_the_iidm_flag():
    assert N_PARAMS == 10
    assert _params(FLEETS["iidm"], 1)[P_IIDM] == 1.0
    assert _params(FLEETS["idm"], 1)[P_IIDM] == 0.0


def test_iidm_changes_the_prediction_of_a_follower():
    """VMC 40 m behind VMF at v0: the IIDM holds its speed, the IDM brakes (Eq. 1's gap term)."""
    consts = np.zeros(N_CONSTS)
    consts[C_DT], consts[C_EMERGENCY] = 0.1, 9.0
    x = np.array([0.0, 500.0, 540.0 + 5.0, -1e9, 600.0, -1e9])
    present = np.array([True, True, True, False, True, False])
    accs = {}
    for variant, fleet in FLEETS.items():
        params = np.tile(_params(fleet, 1), (N_ROLES, 1))
        v = np.full(N_ROLES, params[0, 0])  # everyone at v0
        key = KeyVehicles(x, v, np.zeros(N_ROLES), present, present, present, params)
        _, _, A = counterfactual(key, consts, 3)
        accs[variant] = A[1, VMC]
    assert accs["iidm"] == pytest.approx(0.0, abs=1e-12)
    assert accs["idm"] < -0.1


def test_integration_stops_exactly_at_zero_speed():
    S = new_state(np.zeros(N_ROLES), np.full(N_ROLES, 1.0), np.zeros(N_ROLES),
                  np.ones(N_ROLES, dtype=np.bool_))  # fmt: skip
    S[R_ACC] = -4.0
    integrate(S, 0.5, 9.0)
    np.testing.assert_allclose(S[R_X], 1.0 / 8.0)  # v^2 / (2 b), not v dt - b dt^2 / 2 = 0
    np.testing.assert_array_equal(S[R_V], 0.0)


@settings(max_examples=200, deadline=None)
@given(
    d=st.floats(-10.0, 200.0),
    v_r=st.floats(0.0, 40.0),
    v_f=st.floats(0.0, 40.0),
    delay=st.sampled_from([0.5, 1.0]),
)
def test_critical_scalar_is_the_array_function(d, v_r, v_f, delay):
    expected = critical_acceleration(d, v_r, v_f, delay=delay, min_distance=2.0,
                                     emergency_decel=7.5)  # fmt: skip
    assert critical_accel(d, v_r, v_f, delay, 2.0, 7.5) == float(expected)
    denom = 2.0 * (d - 2.0 - v_r * delay + v_f**2 / 15.0)
    if denom > 1e-6:
        assert float(expected) == pytest.approx(v_r**2 / denom, rel=1e-12)
    elif denom <= 0.0:
        assert float(expected) == np.inf


def test_created_pair_safety_is_eq15_of_vr_behind_vmf():
    """Longitudinal mode at merge completion: the pairs VR-VMF and VMC-VR, worst of both."""
    from hcomc.control.hierarchical.problem_setup import problem_constants

    config = load_config("C1")
    consts = problem_constants(config, Ramp.of(config.road))
    params = np.tile(_params(FLEETS["idm"], 1), (N_ROLES, 1))
    x = np.array([500.0, 470.0, 540.0, 400.0, 560.0, 450.0])
    v = np.array([25.0, 27.0, 26.0, 25.0, 30.0, 30.0])
    y = np.array([0.0, 0.0, 0.0, 0.0, 3.75, 3.75])
    flags = np.ones(N_ROLES, dtype=np.bool_)
    got = created_pairs_safety(x, v, y, flags, flags, params, False, consts)
    c = config.control
    pairs = [(40.0 - 5.0, 25.0, 26.0), (30.0 - 5.0, 27.0, 25.0)]
    want = max(float(critical_acceleration(d, vr, vf, delay=c.safety_delay_cav,
                                           min_distance=c.safety_min_distance,
                                           emergency_decel=c.safety_emergency_decel))
               for d, vr, vf in pairs)  # fmt: skip
    assert got == want


def test_default_vv0_start_is_the_equilibrium_gap_ahead():
    params = np.tile(_params(FLEETS["idm"], 1), (N_ROLES, 1))
    x0, v0 = np.arange(6.0) * 10.0, np.full(6, 20.0)
    starts = resolve_starts(x0, v0, params, np.full(4, np.nan))
    gap = float(equilibrium_gap(20.0, v0=params[0, 0], T=params[0, 1], s0=params[0, 2],
                                delta=params[0, 5]))  # fmt: skip
    np.testing.assert_allclose(starts, [x0[VR] + params[2, 7] + gap, 20.0, x0[2], v0[2]])
    # at or above v0 the gap is the (finite) one just below v0
    assert np.isfinite(resolve_starts(x0, v0 * 2.0, params, np.full(4, np.nan))).all()


def test_no_equation_is_reimplemented_in_the_rollout():
    """The rollout modules call the homes: no power (IDM), tanh (Eq. 3, 14), square root
    (Eq. 1) or exponential appears in their code, and each module stays small."""
    banned = {"tanh", "sqrt", "exp", "arctanh", "power"}
    for path in sorted(SRC.glob("rollout*.py")):
        text = path.read_text(encoding="utf-8")
        for node in ast.walk(ast.parse(text)):
            assert not (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow)), path.name
            assert not (isinstance(node, ast.Attribute) and node.attr in banned), path.name
        assert len(text.splitlines()) <= 300, path.name
