"""What the channel, a fault and the shield read of the run they act on.

They act between two steps of a run of either engine, as one step listener
(:class:`hcomc.robustness.impairments.Impairments`), and see the run through
:class:`hcomc.interface.listener.ListenedRun` only; this module holds what they share.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from hcomc.interface.listener import ListenedRun

__all__ = ["DrivenVehicles", "broadcast_state"]


class DrivenVehicles(Protocol):
    """A fault as the shield asks it: whether it drives a vehicle now."""

    def drives(self, i: int) -> bool:
        """Whether vehicle ``i`` is driven by the fault (so not by the shield)."""
        ...


def broadcast_state(run: ListenedRun) -> dict[str, np.ndarray]:
    """The state a vehicle's message carries (x, v, a, lane, on the road, changing lanes),
    for every vehicle of ``run`` (the arrays themselves: a receiver copies what it keeps)."""
    return {"x": run.x, "v": run.v, "a": run.a, "lane": run.lane, "active": run.active,
            "changing": run.origin != run.target}  # fmt: skip
