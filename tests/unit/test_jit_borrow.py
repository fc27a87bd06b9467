"""Borrowed views (hcomc._jit.borrow_all) and the compiled step's state handle built on them
(hcomc.sim.step.state.Core): the same memory, no ownership, and the handle keeps what it
borrows alive."""

from __future__ import annotations

import gc
import weakref

import numba
import numpy as np
import pytest

from hcomc._jit import borrow_all, kernel
from hcomc.config import load_config
from hcomc.sim.engine import Simulation
from hcomc.sim.step.build import adopt_log_columns
from hcomc.sim.step.state import Core


@numba.njit
def _views(a, b, c):
    return borrow_all((a, b, c))


@kernel
def _log_x(c):
    return c.log_x


@kernel
def _x(c):
    return c.x


def _owned_by_nobody(view: np.ndarray, owner: np.ndarray) -> bool:
    return view.base is None and not view.flags.owndata and np.shares_memory(view, owner)


def test_borrowed_views_are_the_same_memory_typed_as_given_and_own_nothing():
    a = np.arange(5.0)
    b = np.arange(12, dtype=np.int8).reshape(3, 4)
    c = np.arange(24.0).reshape(2, 3, 4)[:, ::2, 1:]  # not contiguous: layout "A"
    views = _views(a, b, c)
    for view, given in zip(views, (a, b, c), strict=True):
        assert numba.typeof(view) == numba.typeof(given)
        assert view.dtype == given.dtype
        assert view.strides == given.strides
        np.testing.assert_array_equal(view, given)
        assert _owned_by_nobody(view, given)
    views[0][2] = -1.0  # a write through the view is a write to the array
    assert a[2] == -1.0


def test_borrow_all_takes_a_tuple_of_arrays_only():
    with pytest.raises(numba.TypingError):
        _views(np.zeros(2), 1.0, np.zeros(2))


def test_the_step_state_borrows_its_arrays_and_follows_a_grown_log():
    sim = Simulation(load_config("C1"), 0)
    assert _owned_by_nobody(_x(sim.core), sim.arrays.x)
    old = sim.arrays.log_x
    sim.log.grow_slots(2 * sim.log.n_slots)
    sim.arrays = adopt_log_columns(sim.arrays, sim.core, sim.log)
    assert sim.arrays.log_x is not old
    assert sim.arrays.log_x.shape[1] == 2 * old.shape[1]
    assert _owned_by_nobody(_log_x(sim.core), sim.arrays.log_x)


def test_the_step_state_keeps_the_arrays_it_borrows_alive():
    sim = Simulation(load_config("C1"), 0)
    core, x = sim.core, weakref.ref(sim.arrays.x)
    del sim
    gc.collect()
    assert x() is not None  # the simulation is gone, its state handle holds the arrays
    assert isinstance(core, Core)
    del core
    gc.collect()
    assert x() is None
