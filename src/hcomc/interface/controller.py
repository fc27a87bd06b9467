"""The merge-controller protocol: what every controller (HCOMC, the baselines, yours) is."""

from __future__ import annotations

import time
from typing import Protocol

import numpy as np

from hcomc.interface.plan import MergeGroup, MergePlan
from hcomc.interface.view import TrafficView


def elapsed_ms(start: float) -> float:
    """Milliseconds since ``start`` (a :func:`time.perf_counter` value): a decision's time."""
    return (time.perf_counter() - start) * 1000.0


class MergeController(Protocol):
    """Plans the merge of one ramp vehicle."""

    name: str

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        """Decide how VR merges and how the key vehicles cooperate."""
        ...
