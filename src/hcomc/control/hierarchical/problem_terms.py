"""The terms the HCOMC merge problem is stated in: its objectives, constraints, sequences and
modes, the key vehicles' state it is posed on, and the prediction it answers with.

The names of the objectives and constraints (the columns of ``F`` and ``G``), the merge
sequences and the threshold of the mode "none" are those of the decision vector described in
:mod:`hcomc.control.hierarchical.problem`; :class:`KeyState` holds the six key vehicles at the
planning instant, :class:`Prediction` the rolled-out candidates, :func:`problem_constants` the
rollout's constants read from the scenario, and :func:`default_starts` the virtual vehicles'
start states of a first plan.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import ScenarioConfig
from hcomc.control.prediction.population import (
    C_A_MERG,
    C_ACCEL_END,
    C_D,
    C_DELAY_CAV,
    C_DELAY_HDV,
    C_DT,
    C_EMERGENCY,
    C_GAMMA,
    C_POLITENESS,
    C_VMC_DUR,
    C_VV_DECEL,
    C_WIDTH,
    N_CONSTS,
    N_STARTS,
    P_A,
    P_V0,
    VMC,
    KeyVehicles,
)
from hcomc.models.transition import transition_gamma
from hcomc.safety.critical import SafetyIndex

__all__ = [
    "AHEAD",
    "BEHIND",
    "CONSTRAINTS",
    "G_LATERAL",
    "G_SEQUENCE",
    "MODE_NONE",
    "OBJECTIVES",
    "SEQUENCES",
    "KeyState",
    "Prediction",
    "default_starts",
    "problem_constants",
]

OBJECTIVES: tuple[str, ...] = ("safety", "fuel", "efficiency")
CONSTRAINTS = (
    "collision",
    "not_merged",
    "unsafe",
    "virtual_vehicle",
    "overrun",
    "lateral",
    "sequence",
)
SEQUENCES = ("ahead", "behind")
AHEAD, BEHIND = 0, 1
MODE_NONE = 1.0
"""With ``control.no_cooperation`` (HCOMC+) the mode variable spans [0, 1.5]: a value of at
least this asks for no cooperation (VMC keeps car following); without it the variable spans
[0, 1] and every row cooperates."""
G_LATERAL, G_SEQUENCE = CONSTRAINTS.index("lateral"), CONSTRAINTS.index("sequence")
"""Columns of ``G`` of the lateral and sequence constraints, which the problem sets itself (the
rollout's kernel writes the others)."""


@dataclass(frozen=True, slots=True)
class KeyState:
    """State and parameters of the six key vehicles at planning time (roles VR … VNR).

    Missing VMF/VNF are replaced by a phantom far ahead at VMC's speed (free road); missing
    VMR/VNR are absent (``present`` False). ``coop`` says which roles cooperate when their
    mode asks it (normally the CAVs); ``starts`` are the start states of VV0 and VV1 (NaN:
    the paper's Eq. 8 start; a replanning controller continues the live virtual vehicles).
    """

    t0: float
    x: FloatArray
    v: FloatArray
    a: FloatArray
    present: BoolArray
    cav: BoolArray
    coop: BoolArray
    params: FloatArray  # (6, 10): v0, T, s0, a, b, delta, coolness, length, width, iidm
    ids: IntArray  # (6,) vehicle indices in the simulation, -1 for absent or phantom
    starts: FloatArray  # (4,) VV0 x, v and VV1 x, v (NaN = default)

    def desired_speed(self, role: int) -> float:
        """Desired speed v0 of a role [m/s] (Eq. 1)."""
        return float(self.params[role, P_V0])

    def max_accel(self, role: int) -> float:
        """Maximum acceleration a of a role [m/s^2] (Eq. 1)."""
        return float(self.params[role, P_A])

    def vehicles(self) -> KeyVehicles:
        """The arrays of the key vehicles as the prediction kernels take them."""
        return KeyVehicles(self.x, self.v, self.a, self.present, self.cav, self.coop, self.params)

    def with_vmc_cooperation(self, cooperates: bool) -> KeyState:
        """This state with the VMC role's ``coop`` flag set to ``cooperates``: the rollout
        makes that role follow VV1 iff the flag is set (the Eq. 15 delays still follow the
        vehicles' true kinds)."""
        coop = self.coop.copy()
        coop[VMC] = cooperates
        return replace(self, coop=coop)


@dataclass(frozen=True, slots=True)
class Prediction:
    """Predicted trajectories (C, K + 1, 6) and objective parts of candidate plans."""

    t: FloatArray
    X: FloatArray
    Y: FloatArray
    V: FloatArray
    A: FloatArray
    heading: FloatArray
    k_merge: IntArray
    F: FloatArray
    G: FloatArray
    vv0: FloatArray
    vv1: FloatArray
    vv2: FloatArray
    sequence: IntArray  # (C,) AHEAD or BEHIND


def problem_constants(config: ScenarioConfig) -> FloatArray:
    """The rollout's constants vector, every value read from ``config``."""
    safety = SafetyIndex.from_config(config.control)
    consts = np.zeros(N_CONSTS)
    consts[C_DT] = config.control.prediction_dt
    consts[C_ACCEL_END] = config.road.accel_lane_end
    consts[C_WIDTH] = config.road.lane_width
    consts[C_VMC_DUR] = config.cav.lane_change_duration
    consts[C_GAMMA] = transition_gamma(config.lane_change.transition_tolerance)
    consts[C_EMERGENCY] = config.lane_change.emergency_decel
    consts[C_VV_DECEL] = config.control.virtual_max_decel
    consts[C_POLITENESS] = config.lane_change.politeness
    consts[C_D] = safety.min_distance
    consts[C_A_MERG] = safety.emergency_decel
    consts[C_DELAY_CAV] = safety.delay_cav
    consts[C_DELAY_HDV] = safety.delay_hdv
    return consts


def default_starts() -> FloatArray:
    """Start states of VV0 and VV1 for a first plan: the Eq. 8 defaults (all NaN)."""
    return np.full(N_STARTS, np.nan)
