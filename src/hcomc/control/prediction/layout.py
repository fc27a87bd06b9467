"""Array layouts of the HCOMC prediction kernels (:mod:`hcomc.control.prediction.population`).

The compiled kernels exchange arrays; this module names their rows and columns (the six
key-vehicle roles, the per-role model parameters, the constants read from the config, the
start states of the virtual vehicles, the constraint columns and the lane-change progress of
one candidate) and the records that group the arrays passed together: the key vehicles
(:class:`KeyVehicles`), one candidate's trajectories (:class:`Trajectories`) and the passes'
scratch space (:class:`Scratch`). The records are ``NamedTuple`` classes, which numba takes as
arguments and builds in compiled code.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hcomc.road import KEY_ROLES, VMC, VMF, VMR, VNF, VNR, VR

__all__ = ["VMC", "VMF", "VMR", "VNF", "VNR", "VR"]  # the role indices, from hcomc.road
N_ROLES = len(KEY_ROLES)
N_PAIRS = N_ROLES * (N_ROLES - 1) // 2  # key-vehicle pairs i < j, row-major

# params columns: Eq. 1 / Eq. 3 parameters, body size, and whether the base model is the IIDM
P_V0, P_T, P_S0, P_A, P_B, P_DELTA, P_C, P_LEN, P_WID, P_IIDM = range(10)
N_PARAMS = 10

# constants vector
(
    C_DT,
    C_ACCEL_END,
    C_WIDTH,
    C_VMC_DUR,
    C_GAMMA,
    C_EMERGENCY,
    C_VV_DECEL,
    C_POLITENESS,
    C_D,
    C_A_MERG,
    C_DELAY_CAV,
    C_DELAY_HDV,
    C_REPLAN,  # replan period [s] of HCOMC-R; 0 (planning once): G_NO_RETURN, G_EXECUTION off
    C_B_SAFE,  # MOBIL's safe deceleration b_safe [m/s^2] (the engine's execution criterion)
    C_MIN_GAP,  # MOBIL's minimum bumper gap to accept [m] (the same criterion)
) = range(15)
N_CONSTS = 15

# start states of the virtual vehicles VV0 and VV1 (NaN: the Eq. 8 default)
S_VV0_X, S_VV0_V, S_VV1_X, S_VV1_V = range(4)
N_STARTS = 4

# constraint columns, in the order of the merge problem's constraints
# (hcomc.control.hierarchical.problem_terms.CONSTRAINTS); columns 5 and 6 are the problem's own
# (lateral mode not admitted, "behind" without a vehicle), left 0 by the kernels;
# G_NO_RETURN and G_EXECUTION only with C_REPLAN > 0, else 0
G_COLLISION, G_NOT_MERGED, G_UNSAFE, G_VIRTUAL, G_OVERRUN = range(5)
G_NO_RETURN, G_EXECUTION = 7, 8
N_G = 9

# lane-change progress of one candidate in one pass (flags stored as 0.0 / 1.0)
(
    L_VR_STARTED,  # VR has begun its change to lane 1
    L_VR_DONE,  # ... and ended it
    L_VR_T0,  # time the change began [s]
    L_VR_X0,  # start and predicted end of VR's quintic path [m]
    L_VR_XF,
    L_LATERAL,  # the cooperating VMC changes to lane 2 (lateral mode)
    L_VMC_DONE,  # ... and has ended that change (or never changes)
    L_VMC_X0,  # start and predicted end of VMC's quintic path [m]
    L_VMC_XF,
) = range(9)
N_PROGRESS = 9

# rows of the state of the roles during one pass: position, speed, acceleration, commanded
# acceleration of the next step, lane-1 and lane-2 membership and presence (flags 0.0 / 1.0),
# and the free-road term of the car-following model at the current speed (NaN until taken:
# a role evaluated behind several leaders in one step takes its power once)
R_X, R_V, R_A, R_ACC, R_IN1, R_IN2, R_PRESENT, R_FREE = range(8)
N_STATE = 8

LANE0 = np.array([0, 1, 1, 1, 2, 2])  # lanes of the roles at planning time (0 = ramp)


class KeyVehicles(NamedTuple):
    """The six key vehicles at the planning instant, each array (6,) in role order VR … VNR."""

    x: np.ndarray  # position [m]
    v: np.ndarray  # speed [m/s]
    a: np.ndarray  # acceleration [m/s^2]
    present: np.ndarray  # bool: the role exists
    cav: np.ndarray  # bool: the role is a CAV (its Eq. 15 delay; a CAV VR follows VV0)
    coop: np.ndarray  # bool: the role cooperates when its mode asks it (VMC: VV1 or lateral)
    params: np.ndarray  # (6, N_PARAMS) model parameters, columns P_*


class Trajectories(NamedTuple):
    """One candidate's predicted trajectories, each (K + 1, 6): step k, role."""

    x: np.ndarray  # position [m]
    y: np.ndarray  # lateral position [m] (lane 1 at 0, the ramp at -width, lane 2 at width)
    v: np.ndarray  # speed [m/s]
    a: np.ndarray  # acceleration [m/s^2]
    heading: np.ndarray  # heading [rad]


class Scratch(NamedTuple):
    """Scratch space of one candidate's passes (pre-pass and joint pass), overwritten by
    each; a population or a run of rows allocates it once."""

    state: np.ndarray  # (N_STATE, 6) the roles' state S (rows R_*)
    progress: np.ndarray  # (N_PROGRESS,) the lane-change progress lc (L_*)
    boxes: np.ndarray  # (4, 6) the bounding boxes of the collision test of one step
    vr_acc: np.ndarray  # (max(K, 1),) VR's accelerations in the pre-pass's steps [m/s^2]
