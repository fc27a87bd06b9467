"""Fixtures of the controller tests."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from hcomc.control.prediction.layout import N_ROLES
from hcomc.control.prediction.step import new_state

RoleState = Callable[[dict[int, float], dict[int, float]], np.ndarray]


@pytest.fixture
def role_state() -> RoleState:
    """``role_state(x, v)``: the merge prediction's state S of the key-vehicle roles at the
    positions ``x`` and speeds ``v`` (role -> value; a role not in ``x`` is absent),
    accelerations 0."""

    def make(x: dict[int, float], v: dict[int, float]) -> np.ndarray:
        present = np.array([r in x for r in range(N_ROLES)])
        xs = np.array([x.get(r, -1e9) for r in range(N_ROLES)])
        vs = np.array([v.get(r, 0.0) for r in range(N_ROLES)])
        return new_state(xs, vs, np.zeros(N_ROLES), present)

    return make
