"""Eq. 17 with the accelerations before and after VR's lane change (paper Section III-C-1c:
"acceleration before and after lane change").

"Before" is the predicted state in which VR begins its change, VR on the acceleration lane at
its free-road acceleration and the others behind their lanes' leaders without VR; "after" the
predicted state in which VR completes it, VR in lane 1 behind its leader there and the others
with VR in lane 1 (lateral mode: the cooperating VMC in lane 2). The expected values are
computed by hand with the IDM of :func:`hcomc.equations.idm.idm_accel`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from hcomc.control.prediction.layout import N_PARAMS, N_ROLES
from hcomc.control.prediction.scoring import (
    accels_after,
    accels_before,
    lane_change_incentive,
)
from hcomc.equations.idm import idm_accel
from hcomc.equations.incentive import mobil_incentive
from hcomc.road import VMC, VMF, VMR, VNF, VNR, VR

V0, T, S0, A_MAX, B, DELTA, LENGTH = 33.3, 1.0, 2.0, 1.4, 2.0, 4.0, 5.0
ETA = 0.5


def _params() -> np.ndarray:
    """Every role an IDM car (coolness 0, not the IIDM): v0, T, s0, a, b, delta, c, L, W, iidm."""
    row = np.array([V0, T, S0, A_MAX, B, DELTA, 0.0, LENGTH, 1.8, 0.0])
    assert row.size == N_PARAMS
    return np.tile(row, (N_ROLES, 1))


def _idm(x: dict[int, float], v: dict[int, float], r: int, lead: int | None) -> float:
    """IDM acceleration of role r behind ``lead`` (None: free road), by hand."""
    if lead is None:
        return float(idm_accel(np.inf, v[r], 0.0, V0, T, A_MAX, B, S0, DELTA))
    gap = x[lead] - LENGTH - x[r]
    return float(idm_accel(gap, v[r], v[r] - v[lead], V0, T, A_MAX, B, S0, DELTA))


# every role present, "before" (VR begins its change) and "after" (VR completed it)
X_BEFORE = {VR: 760.0, VMC: 740.0, VMF: 800.0, VMR: 700.0, VNF: 820.0, VNR: 760.0}
V_BEFORE = {VR: 22.0, VMC: 25.0, VMF: 25.0, VMR: 24.0, VNF: 27.0, VNR: 26.0}
X_AFTER = {VR: 900.0, VMC: 870.0, VMF: 930.0, VMR: 830.0, VNF: 960.0, VNR: 900.0}
V_AFTER = {VR: 24.0, VMC: 25.0, VMF: 25.0, VMR: 24.0, VNF: 27.0, VNR: 26.0}


def test_before_is_the_arrangement_before_the_change_in_its_own_state(
    role_state: Callable[..., np.ndarray],
):
    """VR at its free-road acceleration; VMC behind VMF, VMR behind VMC, VNR behind VNF."""
    x, v = X_BEFORE, V_BEFORE
    a_vr, others = accels_before(role_state(x, v), _params())
    assert a_vr == pytest.approx(_idm(x, v, VR, None), rel=1e-12)
    want = _idm(x, v, VMC, VMF) + _idm(x, v, VMR, VMC) + _idm(x, v, VNR, VNF)
    assert others == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("lateral", [False, True])
def test_after_is_vr_in_lane_1_in_the_state_it_completes_its_change(
    lateral, role_state: Callable[..., np.ndarray]
):
    """Longitudinal: VR behind VMF, VMC behind VR, VMR behind VMC, VNR behind VNF. Lateral:
    VMC in lane 2 behind VNR (the nearest ahead there), VMR behind VR, VNR behind VNF."""
    x, v = X_AFTER, V_AFTER
    a_vr, others = accels_after(role_state(x, v), _params(), lateral)
    assert a_vr == pytest.approx(_idm(x, v, VR, VMF), rel=1e-12)
    if lateral:
        want = _idm(x, v, VMC, VNR) + _idm(x, v, VMR, VR) + _idm(x, v, VNR, VNF)
    else:
        want = _idm(x, v, VMC, VR) + _idm(x, v, VMR, VMC) + _idm(x, v, VNR, VNF)
    assert others == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("lateral", [False, True])
def test_u_eff_compares_the_two_states(lateral, role_state: Callable[..., np.ndarray]):
    """U_eff = (a_VR,after - a_VR,before) + eta sum_i (a_i,after - a_i,before) over two
    different predicted states, in closed form."""
    xb, vb, xa, va = X_BEFORE, V_BEFORE, X_AFTER, V_AFTER
    before = _idm(xb, vb, VMC, VMF) + _idm(xb, vb, VMR, VMC) + _idm(xb, vb, VNR, VNF)
    if lateral:
        after = _idm(xa, va, VMC, VNR) + _idm(xa, va, VMR, VR) + _idm(xa, va, VNR, VNF)
    else:
        after = _idm(xa, va, VMC, VR) + _idm(xa, va, VMR, VMC) + _idm(xa, va, VNR, VNF)
    want = (_idm(xa, va, VR, VMF) - _idm(xb, vb, VR, None)) + ETA * (after - before)
    got = lane_change_incentive(role_state(xb, vb), role_state(xa, va), _params(), lateral, ETA)
    assert got == pytest.approx(want, rel=1e-12)
    assert got == pytest.approx(
        mobil_incentive(_idm(xa, va, VR, VMF) - _idm(xb, vb, VR, None), after - before, ETA)
    )


def test_behind_plan_beside_its_future_leader_no_longer_scores_zero(
    role_state: Callable[..., np.ndarray],
):
    """A "behind" plan (roles relabelled: VMF is the vehicle VR will follow, VMC the one that
    will follow VR) in which VR begins its change beside its future leader (1 m ahead of its
    front bumper) and, once in lane 1, has to brake behind it.

    Read in the start state alone (the former Eq. 17), VR has nobody ahead in lane 1 and VMC
    keeps VMF as its leader: U_eff = 0, the best score a merge can get. With the state after
    the change, VR's braking enters: U_eff < 0, by hand."""
    params = _params()
    x_b = {VR: 800.0, VMC: 740.0, VMF: 799.0, VNF: 1500.0}
    v_b = {VR: 25.0, VMC: 25.0, VMF: 25.0, VNF: 25.0}
    x_a = {VR: 900.0, VMC: 860.0, VMF: 920.0, VNF: 1600.0}
    v_a = {VR: 26.0, VMC: 25.0, VMF: 25.0, VNF: 25.0}
    start = role_state(x_b, v_b)
    assert lane_change_incentive(start, start, params, False, ETA) == 0.0  # the former bias
    a_vr_after = _idm(x_a, v_a, VR, VMF)
    assert a_vr_after < -2.0  # VR brakes behind its new leader
    want = (a_vr_after - _idm(x_b, v_b, VR, None)) + ETA * (
        _idm(x_a, v_a, VMC, VR) - _idm(x_b, v_b, VMC, VMF)
    )
    got = lane_change_incentive(start, role_state(x_a, v_a), params, False, ETA)
    assert got == pytest.approx(want, rel=1e-12)
    assert got < -2.0
