"""The terms the HCOMC merge problem is stated in: its objectives, constraints, sequences and
modes, the key vehicles' state it is posed on, and the prediction it answers with.

The names of the objectives and constraints (the columns of ``F`` and ``G``), the merge
sequences and the threshold of the mode "none" are those of the decision vector described in
:mod:`hcomc.control.hierarchical.problem`; :class:`KeyState` holds the six key vehicles at the
planning instant, :class:`Prediction` the rolled-out candidates and :func:`default_starts` the
virtual vehicles' start states of a first plan, :func:`decode_rows` what a row of the decision
vector selects and :func:`canonical_form` one row for all that select the same. The compiled row
scoring
(:mod:`~hcomc.control.hierarchical.row_scoring`) reads these terms, so they import no config:
the rollout's constants read from the scenario are
:func:`~hcomc.control.hierarchical.problem_setup.problem_constants`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.control.prediction.population import N_STARTS, P_A, P_V0, VMC, KeyVehicles

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
    "canonical_form",
    "decode_rows",
    "default_starts",
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
    "no_return",
    "execution",
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


def default_starts() -> FloatArray:
    """Start states of VV0 and VV1 for a first plan: the Eq. 8 defaults (all NaN)."""
    return np.full(N_STARTS, np.nan)


@kernel
def decode_rows(
    X: FloatArray, no_cooperation: bool, has_behind: bool
) -> tuple[IntArray, BoolArray, IntArray, BoolArray]:
    """What each row of the decision vector ``X`` (n, 5) selects: its merge sequence (AHEAD or
    BEHIND), its lateral flag, its variant (the group it is rolled out in: sequence + 2 for
    the mode "none") and whether it asked to merge behind without a vehicle to merge behind
    (``has_behind`` false: it is rolled out ahead). The mode variable x[3] asks for "none"
    from :data:`MODE_NONE` (with ``no_cooperation`` only), else for lateral cooperation from
    0.5; the sequence variable x[4] for "behind" from 0.5; a lateral row merges ahead (the
    cooperating vehicle leaves, VR takes its slot). A NaN selects neither."""
    n = X.shape[0]
    seq, lateral = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.bool_)
    variant, no_behind = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.bool_)
    for r in range(n):
        none = X[r, 3] >= MODE_NONE and no_cooperation
        lateral[r] = X[r, 3] >= 0.5 and not none
        behind = X[r, 4] >= 0.5 and not lateral[r]
        no_behind[r] = behind and not has_behind
        seq[r] = BEHIND if behind and has_behind else AHEAD
        variant[r] = seq[r] + 2 * none
    return seq, lateral, variant, no_behind


@kernel
def canonical_form(X: FloatArray, no_cooperation: bool, has_behind: bool) -> FloatArray:
    """``X`` with the mode and sequence variables set to one value of what they select
    (:func:`decode_rows`): mode 0 (longitudinal), 0.5 (lateral) or :data:`MODE_NONE`;
    sequence 1 for a row rolled out behind or asking to be, 0 otherwise. Rows with equal
    canonical rows are the same candidate."""
    seq, lateral, variant, no_behind = decode_rows(X, no_cooperation, has_behind)
    out = X.copy()
    for r in range(X.shape[0]):
        out[r, 3] = MODE_NONE if variant[r] >= 2 else 0.5 if lateral[r] else 0.0
        out[r, 4] = 1.0 if seq[r] == BEHIND or no_behind[r] else 0.0
    return out
