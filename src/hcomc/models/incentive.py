"""The acceleration incentive of a lane change (paper Eq. 17; MOBIL).

MOBIL (Kesting, Treiber & Helbing, "General lane-changing model MOBIL for car-following
models", Transportation Research Record 1999, 2007) weighs the change of the changing
vehicle's own acceleration against the changes it causes to the vehicles around it, with a
politeness factor. The paper's efficiency objective U_eff (Eq. 17) is this incentive for VR's
merge, summed over VMC, VMR and VNR; the engine's discretionary lane changes use it over the
new and the old follower. One function for both.
"""

from __future__ import annotations

from hcomc._jit import kernel


@kernel(inline="always")
def mobil_incentive(own_change: float, others_change: float, politeness: float) -> float:
    """U_eff of Eq. 17, ``Δa_own + η Σ Δa_others`` [m/s^2].

    own_change : the changing vehicle's acceleration after the change minus before [m/s^2].
    others_change : the sum of the same difference over the vehicles the change affects
        [m/s^2].
    politeness : η, the weight of the others' changes [-].
    """
    return own_change + politeness * others_change
