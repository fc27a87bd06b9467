"""Per-step kernels of the HCOMC prediction: car following of a role, leaders, integration.

Every equation is called from its one home: car following (Eq. 1, the IIDM, Eq. 3) from
:func:`hcomc.models.following.follow_accel`, the virtual vehicles' cubics (Eq. 9) from
:func:`hcomc.control.virtual_vehicle.cubic_point`. The ballistic step with a stop at v = 0 is
the engine's integration scheme.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hcomc.control.hcomc.rollout_layout import (
    N_ROLES,
    P_A,
    P_B,
    P_C,
    P_DELTA,
    P_IIDM,
    P_LEN,
    P_S0,
    P_T,
    P_V0,
)
from hcomc.control.virtual_vehicle import cubic_point
from hcomc.models.following import follow_accel


@njit(cache=True, inline="always")
def follow_role(params: np.ndarray, r: int, s: float, v: float, vl: float, al: float) -> float:
    """Car-following acceleration of role r (parameter row ``params[r]``) [m/s^2].

    ``s`` is the gap to the leader (``inf``: free road); IDM or IIDM per ``params[r, P_IIDM]``.
    """
    p = params
    return follow_accel(
        s, v, vl, al, p[r, P_V0], p[r, P_T], p[r, P_S0], p[r, P_A], p[r, P_B], p[r, P_DELTA],
        p[r, P_C], p[r, P_IIDM] > 0.5,
    )  # fmt: skip


@njit(cache=True, inline="always")
def free_road(params: np.ndarray, r: int, v: float) -> float:
    """Acceleration of role r without a leader [m/s^2]."""
    return follow_role(params, r, np.inf, v, v, 0.0)


@njit(cache=True, inline="always")
def leader(
    r: int, lane: int, x: np.ndarray, in1: np.ndarray, in2: np.ndarray, present: np.ndarray
) -> int:
    """Nearest key vehicle strictly ahead of role r in ``lane`` (1 or 2), -1 if none."""
    best, best_x = -1, np.inf
    for j in range(N_ROLES):
        if j == r or not present[j]:
            continue
        member = in1[j] if lane == 1 else in2[j]
        if member and x[r] < x[j] < best_x:
            best, best_x = j, x[j]
    return best


@njit(cache=True, inline="always")
def behind(
    r: int, j: int, x: np.ndarray, v: np.ndarray, a: np.ndarray, params: np.ndarray
) -> float:
    """Acceleration of role r behind role j (free road for j = -1) [m/s^2]."""
    if j < 0:
        return free_road(params, r, v[r])
    return follow_role(params, r, x[j] - params[j, P_LEN] - x[r], v[r], v[j], a[j])


@njit(cache=True, inline="always")
def behind_virtual(
    params: np.ndarray, r: int, x: float, v: float, vvs: np.ndarray, i: int, tau: float,
    lead_len: float,
) -> float:  # fmt: skip
    """Acceleration of role r (at x, v) behind the cubic virtual vehicle ``vvs[i]`` at ``tau``
    (length ``lead_len``)."""
    xv, vv, av = cubic_point(vvs[i, 0], vvs[i, 1], vvs[i, 2], vvs[i, 3], tau)
    return follow_role(params, r, xv - lead_len - x, v, vv, av)


@njit(cache=True, inline="always")
def integrate(
    x: np.ndarray,
    v: np.ndarray,
    a: np.ndarray,
    acc: np.ndarray,
    present: np.ndarray,
    dt: float,
    emergency: float,
) -> None:
    """Ballistic step of every present role, stopping exactly at v = 0 (as the engine)."""
    for r in range(N_ROLES):
        if not present[r]:
            continue
        ar = max(acc[r], -emergency)
        v1 = v[r] + ar * dt
        if v1 < 0.0:
            x[r] += -v[r] * v[r] / (2.0 * ar) if ar < 0.0 else 0.0
            a[r] = -v[r] / dt
            v[r] = 0.0
        else:
            x[r] += v[r] * dt + 0.5 * ar * dt * dt
            v[r] = v1
            a[r] = ar
