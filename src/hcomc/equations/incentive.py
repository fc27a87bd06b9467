r"""The acceleration incentive of a lane change, paper Eq. (17), MOBIL's incentive.

The paper's efficiency index of a merge is "the acceleration incentive model": the change of
the merging vehicle's own acceleration plus the politeness-weighted changes it causes to the
vehicles around it,

.. math::
   U_\mathrm{eff} = a_{(VR)\mathrm{new}} - a_{(VR)\mathrm{ori}}
                    + \eta \sum_{i=1}^{N} \left(a_{(i)\mathrm{new}} - a_{(i)\mathrm{ori}}\right)

over VMC, VNR and VMR, which is the incentive criterion of MOBIL (Kesting, Treiber & Helbing
2007). The engine's discretionary lane changes take the same incentive over the new and the
old follower; both call :func:`mobil_incentive`.

References
----------
.. [1] A. Kesting, M. Treiber and D. Helbing, "General lane-changing model MOBIL for
   car-following models", Transportation Research Record 1999, 86-94 (2007).
.. [2] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section III-C-1, Eq. (17).
"""

from __future__ import annotations

from hcomc._jit import kernel

__all__ = ["mobil_incentive"]


@kernel(inline="always")
def mobil_incentive(own_change: float, others_change: float, politeness: float) -> float:
    r"""Acceleration incentive of a lane change, :math:`U_\mathrm{eff}` of paper Eq. (17).

    .. math::
       :label: eq-17-incentive

       U_\mathrm{eff} = \Delta a_\mathrm{own} + \eta \sum_i \Delta a_i

    Parameters
    ----------
    own_change : float
        :math:`a_{(VR)\mathrm{new}} - a_{(VR)\mathrm{ori}}`: the changing vehicle's
        acceleration after the change minus before [m/s^2].
    others_change : float
        :math:`\sum_i (a_{(i)\mathrm{new}} - a_{(i)\mathrm{ori}})`: the sum of the same
        difference over the vehicles the change affects [m/s^2] (VMC, VNR and VMR for VR's
        merge; the new and the old follower for a discretionary change).
    politeness : float
        :math:`\eta`, the politeness factor [-]: the weight of the others' changes.

    Returns
    -------
    float
        The incentive [m/s^2]; larger is better for the change.

    Notes
    -----
    The paper calls :math:`a_{(i)\mathrm{new}}` and :math:`a_{(i)\mathrm{ori}}` the
    accelerations "before and after lane change, respectively"; the formula (new minus
    original) and MOBIL fix the sign used here: positive when the change raises the
    accelerations. As an objective to minimise, the HCOMC problem takes
    :math:`-U_\mathrm{eff}`. MOBIL's threshold and keep-right bias are not part of the
    incentive; the caller compares the incentive with them.

    References
    ----------
    .. [1] Kesting, Treiber & Helbing, Transp. Res. Rec. 1999, 86 (2007).
    .. [2] HCOMC paper (arXiv:2507.11621), Eq. (17).
    """
    return own_change + politeness * others_change
