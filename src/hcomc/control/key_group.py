"""The key group of a ramp vehicle in a traffic view (Section II-A): the six key vehicles as a
:class:`~hcomc.interface.MergeGroup`.

The rules are those of :mod:`hcomc.control.key_vehicles`, whose compiled kernels this module
runs on a :class:`~hcomc.interface.TrafficView`; they stay apart from it so that the kernels'
cache depends on the kernels alone, not on the interface and the config it imports.
:func:`find_key_vehicles` gives the group as identified, :func:`behind_group` the group
relabelled for the sequence "VR merges behind VMC".
"""

from __future__ import annotations

from hcomc.control.key_vehicles import key_vehicle_indices, nearest_in_lane
from hcomc.interface import MergeGroup, TrafficView


def _nearest(view: TrafficView, lane: int, x: float, exclude: int) -> tuple[int, int]:
    """:func:`nearest_in_lane` on a view."""
    lead, follow = nearest_in_lane(view.x, view.lane, view.active, int(lane), float(x), exclude)
    return int(lead), int(follow)


def find_key_vehicles(view: TrafficView, vr: int) -> MergeGroup:
    """The six key vehicles of Section II-A around ramp vehicle ``vr`` at the view's ramp
    (rules in :mod:`hcomc.control.key_vehicles`)."""
    ramp = view.ramp
    indices = key_vehicle_indices(view.x, view.lane, view.active, vr, ramp.target, ramp.beyond)
    return MergeGroup(*indices.tolist())


def behind_group(view: TrafficView, group: MergeGroup) -> MergeGroup:
    """Relabelled key group for "VR merges behind VMC" (the old VMR cooperates).

    The vehicle ahead of VR's slot (old VMC) becomes ``vmf``, the vehicle behind it (old VMR)
    becomes ``vmc``, the lane-1 vehicle behind the old VMR becomes ``vmr`` and VNF/VNR are the
    lane-2 neighbours of the old VMR (the rules of :func:`find_key_vehicles`). Without an old
    VMR only ``vr`` and ``vmf`` are set (nobody to cooperate). Requires ``group.vmc >= 0``.
    """
    if group.vmc < 0:
        raise ValueError("behind_group needs a VMC (the vehicle VR merges behind)")
    new_vmc = group.vmr
    if new_vmc < 0:
        return MergeGroup(vr=group.vr, vmf=group.vmc)
    _, vmr = _nearest(view, view.ramp.target, float(view.x[new_vmc]) - 1e-9, new_vmc)
    vnf, vnr = -1, -1
    if view.ramp.beyond >= 0:
        vnf, vnr = _nearest(view, view.ramp.beyond, float(view.x[new_vmc]), new_vmc)
    return MergeGroup(vr=group.vr, vmc=new_vmc, vmf=group.vmc, vmr=vmr, vnf=vnf, vnr=vnr)
