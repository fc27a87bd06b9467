"""The road section of a position (hcomc.sim.step.road): the step's walk from a vehicle's
section at its last step against the binary search, from any start."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.sim.step.road import section_at, section_near


@settings(max_examples=300, deadline=None)
@given(
    starts=st.lists(
        st.sampled_from([0.0, 250.0, 1000.0, 1000.0, 2500.0, 4000.0]), min_size=1, max_size=8
    ).map(sorted),
    x=st.one_of(st.floats(-100.0, 5000.0), st.sampled_from([0.0, 250.0, 1000.0, 4000.0])),
    hint=st.integers(0, 7),
)
def test_the_walk_from_any_section_finds_the_searched_one(starts, x, hint):
    sec_x0 = np.array(starts, dtype=np.float64)
    s = min(hint, sec_x0.size - 1)
    assert section_near(sec_x0, x, s) == section_at(sec_x0, x)


def test_a_nan_position_gets_the_searched_section():
    sec_x0 = np.array([0.0, 500.0, 900.0])
    assert section_near(sec_x0, np.nan, 2) == section_at(sec_x0, np.nan) == 0


def test_sections_of_a_vehicle_driving_down_the_road():
    """A vehicle moving on a step at a time, its section kept from step to step."""
    sec_x0 = np.array([0.0, 300.0, 300.0, 800.0, 1600.0])
    s = 0
    for x in np.arange(-20.0, 2000.0, 2.5):
        s = section_near(sec_x0, float(x), s)
        assert s == section_at(sec_x0, float(x))
