"""Per-step kernels of the prediction: car following of a role, leaders, integration.

Every equation is called from its one home: car following (Eq. 1, the IIDM, Eq. 3) from the
two parts :func:`hcomc.equations.car_following.follow_accel` composes (``free_term``, taken once per
role and step, and ``follow_accel_given``), the virtual vehicles' cubics (Eq. 9) from
:func:`hcomc.equations.virtual_vehicle.cubic_point`, and the integration from
:func:`hcomc.equations.integrate.ballistic_step`, the engine's. The roles' state is one (8, 6)
array ``S`` (rows ``R_*`` of :mod:`hcomc.control.prediction.layout`), so that the compiled
kernels pass few arrays.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc.control.prediction.layout import (
    LANE0,
    N_ROLES,
    N_STATE,
    P_A,
    P_B,
    P_C,
    P_DELTA,
    P_IIDM,
    P_LEN,
    P_S0,
    P_T,
    P_V0,
    R_A,
    R_ACC,
    R_FREE,
    R_IN1,
    R_IN2,
    R_PRESENT,
    R_V,
    R_X,
)
from hcomc.equations.car_following import follow_accel_given, free_term
from hcomc.equations.integrate import ballistic_step
from hcomc.equations.virtual_vehicle import cubic_point


@kernel(inline="always")
def follow_role(S: np.ndarray, params: np.ndarray, r: int, s: float, vl: float, al: float) -> float:
    """Car-following acceleration of role r at its speed ``S[R_V, r]`` (parameter row
    ``params[r]``) [m/s^2].

    ``s`` is the gap to the leader (``inf``: free road); IDM or IIDM per ``params[r, P_IIDM]``.
    The free-road term is taken once per step and role (row ``R_FREE``, NaN until taken).
    """
    p = params
    free = S[R_FREE, r]
    if math.isnan(free):
        free = free_term(S[R_V, r], p[r, P_V0], p[r, P_A], p[r, P_B], p[r, P_DELTA],
                         p[r, P_IIDM] > 0.5)  # fmt: skip
        S[R_FREE, r] = free
    return follow_accel_given(
        s, S[R_V, r], vl, al, p[r, P_V0], p[r, P_T], p[r, P_S0], p[r, P_A], p[r, P_B],
        p[r, P_C], p[r, P_IIDM] > 0.5, free,
    )  # fmt: skip


@kernel(inline="always")
def free_road(S: np.ndarray, params: np.ndarray, r: int) -> float:
    """Acceleration of role r without a leader [m/s^2]."""
    return follow_role(S, params, r, np.inf, S[R_V, r], 0.0)


@kernel(inline="always")
def leader(S: np.ndarray, r: int, lane: int) -> int:
    """Nearest present key vehicle strictly ahead of role r in ``lane`` (1 or 2), -1 if none."""
    row = R_IN1 if lane == 1 else R_IN2
    best, best_x = -1, np.inf
    for j in range(N_ROLES):
        if j != r and S[R_PRESENT, j] and S[row, j] and S[R_X, r] < S[R_X, j] < best_x:
            best, best_x = j, S[R_X, j]
    return best


@kernel(inline="always")
def behind(S: np.ndarray, params: np.ndarray, r: int, j: int) -> float:
    """Acceleration of role r behind role j (free road for j = -1) [m/s^2]."""
    if j < 0:
        return free_road(S, params, r)
    gap = S[R_X, j] - params[j, P_LEN] - S[R_X, r]
    return follow_role(S, params, r, gap, S[R_V, j], S[R_A, j])


@kernel(inline="always")
def behind_virtual(
    S: np.ndarray, params: np.ndarray, r: int, vvs: np.ndarray, i: int, tau: float,
    lead_len: float,
) -> float:  # fmt: skip
    """Acceleration of role r behind the cubic virtual vehicle ``vvs[i]`` at ``tau`` (length
    ``lead_len``) [m/s^2]."""
    xv, vv, av = cubic_point(vvs[i, 0], vvs[i, 1], vvs[i, 2], vvs[i, 3], tau)
    return follow_role(S, params, r, xv - lead_len - S[R_X, r], vv, av)


@kernel(inline="always")
def integrate(S: np.ndarray, dt: float, emergency: float) -> None:
    """Ballistic step of every present role with its acceleration ``S[R_ACC]`` (floored at
    the emergency deceleration), stopping exactly at v = 0 (as the engine)."""
    for r in range(N_ROLES):
        if S[R_PRESENT, r]:
            integrate_role(S, r, dt, emergency)


@kernel(inline="always")
def integrate_role(S: np.ndarray, r: int, dt: float, emergency: float) -> None:
    """The ballistic step of :func:`integrate` for role r alone."""
    dx, S[R_V, r], S[R_A, r] = ballistic_step(S[R_V, r], max(S[R_ACC, r], -emergency), dt)
    S[R_X, r] += dx
    S[R_FREE, r] = np.nan  # a new speed


@kernel
def new_state(x: np.ndarray, v: np.ndarray, a: np.ndarray, present: np.ndarray) -> np.ndarray:
    """The state ``S`` (8, 6) of the roles at planning time (lane rows at their start lanes)."""
    S = np.empty((N_STATE, N_ROLES))
    reset_state(S, x, v, a, present)
    return S


@kernel(inline="always")
def reset_state(
    S: np.ndarray, x: np.ndarray, v: np.ndarray, a: np.ndarray, present: np.ndarray
) -> None:
    """Overwrite ``S`` (8, 6) with the state of :func:`new_state`."""
    S[:] = 0.0
    for r in range(N_ROLES):
        S[R_X, r], S[R_V, r], S[R_A, r] = x[r], v[r], a[r]
        S[R_IN1, r] = 1.0 if LANE0[r] == 1 else 0.0
        S[R_IN2, r] = 1.0 if LANE0[r] == 2 else 0.0
        S[R_PRESENT, r] = 1.0 if present[r] else 0.0
        S[R_FREE, r] = np.nan
