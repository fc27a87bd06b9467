"""What an agent observes: its own state and the six key vehicles of Section II-A around the
ramp vehicle VR, relative to the agent (one compiled kernel, re-identified every step).

Layout of the observation vector (float32, :data:`N_OBS` values):

* 0-4, the agent itself: speed v [m/s], lane (0 ramp and acceleration lane, 1, 2), distance
  to the end of the acceleration lane ``accel_lane_end - x`` [m], changing lanes (0/1),
  progress of its lane change xi = (x - x0) / (xf - x0) in [0, 1] (0 when keeping its lane);
* then five values per key role, in the order VR, VMC, VMF, VMR, VNF, VNR: present (0/1),
  relative position x_r - x [m], relative speed v_r - v [m/s], lane (-1 when absent),
  connected (1 for a CAV). Absent roles are zeros with lane -1.

The key vehicles follow the rules of :func:`hcomc.control.key_group.find_key_vehicles` (the same
kernel), applied to VR's current position.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc.control.key_vehicles import key_vehicle_indices, nearest_in_lane
from hcomc.equations.safety import critical_accel
from hcomc.road import KEY_ROLES, N_ROLES, Lane

N_EGO = 5
"""Values describing the agent itself."""
N_ROLE = 5
"""Values per key role."""
N_OBS = N_EGO + N_ROLE * N_ROLES
"""Length of the observation vector."""

EGO_NAMES = ("v", "lane", "lane_end_distance", "changing", "progress")
ROLE_NAMES = ("present", "dx", "dv", "lane", "cav")
OBS_NAMES: tuple[str, ...] = EGO_NAMES + tuple(
    f"{role}.{name}" for role in KEY_ROLES for name in ROLE_NAMES
)
"""Name of every observation value, in order."""

_MAIN_1, _MAIN_2 = int(Lane.MAIN_1), int(Lane.MAIN_2)  # the paper's road
_V_MAX = 70.0  # [m/s] bound of speeds in the observation space


class Scene(NamedTuple):
    """The vehicles an agent observes, each (N,) by vehicle index."""

    x: np.ndarray  # front-bumper position [m]
    v: np.ndarray  # speed [m/s]
    lane: np.ndarray  # int: current lane (0 ramp and acceleration lane, 1, 2; -1 elsewhere)
    active: np.ndarray  # bool: on the road
    is_cav: np.ndarray  # bool: connected (a CAV)
    length: np.ndarray  # vehicle length [m]
    origin: np.ndarray  # int: lane a lane change started from (= lane when keeping)
    target: np.ndarray  # int: lane a lane change goes to (= lane when keeping)
    lc_x0: np.ndarray  # position where the lane change started [m]
    lc_xf: np.ndarray  # position where it ends [m]


class SafetyParams(NamedTuple):
    """The parameters of Eq. 15 (``config.control.safety_*``) as :func:`pair_safety` takes
    them."""

    delay_cav: float  # delay T of a CAV follower [s]
    delay_hdv: float  # delay T of an HDV follower (reaction + brake) [s]
    min_distance: float  # residual distance D [m]
    a_merg: float  # the leader's emergency deceleration [m/s^2], > 0; the unit of the result


def observation_bounds(road_length: float) -> tuple[np.ndarray, np.ndarray]:
    """``(low, high)`` of the observation space (float32) for a road of this length [m]."""
    ego_low = [0.0, 0.0, -road_length, 0.0, 0.0]
    ego_high = [_V_MAX, 2.0, road_length, 1.0, 1.0]
    role_low = [0.0, -road_length, -_V_MAX, -1.0, 0.0]
    role_high = [1.0, road_length, _V_MAX, 2.0, 1.0]
    low = np.array(ego_low + role_low * N_ROLES, dtype=np.float32)
    high = np.array(ego_high + role_high * N_ROLES, dtype=np.float32)
    return low, high


@kernel
def observe(out: np.ndarray, scene: Scene, ego: int, vr: int, accel_end: float) -> np.ndarray:
    """Write the observation of agent ``ego`` in ``scene`` into ``out`` (``accel_end``: the
    end of the agent's acceleration lane [m]); returns the key vehicles (role order) around
    ``vr``."""
    x, v, lane, active, is_cav, _, origin, target, lc_x0, lc_xf = scene
    group = key_vehicle_indices(x, lane, active, vr, _MAIN_1, _MAIN_2)
    changing = origin[ego] != target[ego]
    out[0] = v[ego]
    out[1] = lane[ego]
    out[2] = accel_end - x[ego]
    out[3] = 1.0 if changing else 0.0
    xi = (x[ego] - lc_x0[ego]) / (lc_xf[ego] - lc_x0[ego]) if changing else 0.0
    out[4] = min(max(xi, 0.0), 1.0)
    for r in range(N_ROLES):
        k = N_EGO + N_ROLE * r
        j = group[r]
        if j < 0:
            out[k : k + N_ROLE] = 0.0
            out[k + 3] = -1.0
            continue
        out[k] = 1.0
        out[k + 1] = x[j] - x[ego]
        out[k + 2] = v[j] - v[ego]
        out[k + 3] = lane[j]
        out[k + 4] = 1.0 if is_cav[j] else 0.0
    return group


@kernel
def pair_safety(scene: Scene, ego: int, params: SafetyParams) -> float:
    """Eq. 15 over agent ``ego``'s follower-leader pairs now, as a fraction of a_merg in
    [0, 1].

    The pairs are the agent behind its leader and its follower behind it, in its lane and,
    during a lane change, also in its target lane; ``inf`` (no deceleration avoids a crash)
    and anything above a_merg count as 1.
    """
    x, v, lane, active, is_cav, length, origin, target, _, _ = scene
    delay_cav, delay_hdv, min_distance, a_merg = params
    worst = 0.0
    lanes = (lane[ego], target[ego] if origin[ego] != target[ego] else lane[ego])
    for in_lane in lanes:
        lead, follow = nearest_in_lane(x, lane, active, in_lane, x[ego], ego)
        if lead >= 0:
            delay = delay_cav if is_cav[ego] else delay_hdv
            d = x[lead] - length[lead] - x[ego]
            worst = max(worst, critical_accel(d, v[ego], v[lead], delay, min_distance, a_merg))
        if follow >= 0:
            delay = delay_cav if is_cav[follow] else delay_hdv
            d = x[ego] - length[ego] - x[follow]
            worst = max(worst, critical_accel(d, v[follow], v[ego], delay, min_distance, a_merg))
    return min(worst / a_merg, 1.0)
