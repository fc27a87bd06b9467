"""A seed's traffic does not depend on the run's duration: a shorter run's demand is exactly
the first vehicles of a longer run's (same times, positions, speeds, lanes, kinds)."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.rng import make_rng
from hcomc.sim.demand import Demand, generate_demand, shifted_exponential

FIELDS = ("t", "x", "v", "lane", "kind", "scripted")
CONDITIONS = ("C1", "C2", "C3", "C4", "C5")


def _demand(condition: str, duration: float, seed: int = 0, **demand: object) -> Demand:
    return generate_demand(load_config(condition, duration=duration, demand=demand), make_rng(seed))


def _assert_prefix(short: Demand, long: Demand, short_duration: float) -> None:
    assert 0 < short.n < long.n
    assert (short.t < short_duration).all()
    for name in FIELDS:
        a, b = getattr(short, name), getattr(long, name)
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b[: short.n], err_msg=name)  # exact equality
    assert (long.t[short.n :] >= short_duration).all()  # the longer run only adds later ones


@pytest.mark.parametrize("condition", CONDITIONS)
@pytest.mark.parametrize(("short", "long"), [(45.0, 50.0), (30.0, 120.0)])
@pytest.mark.parametrize("ramp", ["single", "flow"])
def test_shorter_run_is_a_prefix_of_longer_run(
    condition: str, short: float, long: float, ramp: str
) -> None:
    for seed in (0, 7):
        a = _demand(condition, short, seed, ramp=ramp)
        b = _demand(condition, long, seed, ramp=ramp)
        _assert_prefix(a, b, short)


@pytest.mark.parametrize("condition", CONDITIONS)
def test_uniform_pattern_is_a_prefix_too(condition: str) -> None:
    a = _demand(condition, 45.0, pattern="uniform", ramp="flow")
    b = _demand(condition, 120.0, pattern="uniform", ramp="flow")
    _assert_prefix(a, b, 45.0)


@pytest.mark.parametrize("condition", CONDITIONS)
def test_different_seeds_give_different_demand(condition: str) -> None:
    a, b = _demand(condition, 50.0, 0), _demand(condition, 50.0, 1)
    assert a.n != b.n or not np.array_equal(a.t, b.t)
    assert not np.array_equal(a.x[a.t < -29.0][:5], b.x[b.t < -29.0][:5])  # the fills differ
    # and the same seed gives the same demand
    c = _demand(condition, 50.0, 0)
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(c, name))


def test_the_run_generator_advances_by_a_fixed_amount() -> None:
    """What the engine draws after the demand (estimation errors, controllers) does not
    depend on the duration or the number of vehicles; the uniform pattern draws nothing."""
    states = []
    for duration in (30.0, 45.0, 120.0):
        rng = make_rng(3)
        generate_demand(load_config("C3", duration=duration), rng)
        states.append(rng.bit_generator.state)
    assert states[0] == states[1] == states[2]
    rng = make_rng(3)
    before = rng.bit_generator.state
    generate_demand(load_config("C3", demand={"pattern": "uniform"}), rng)
    assert rng.bit_generator.state == before


def test_shifted_exponential_offsets_are_a_prefix_for_any_span() -> None:
    long = shifted_exponential(np.random.default_rng(5), 3.0, 1.0, 5000.0)
    assert long.size > 1000  # several chunks
    for total in (0.5, 10.0, 767.0, 1234.5, 4999.0):
        short = shifted_exponential(np.random.default_rng(5), 3.0, 1.0, total)
        np.testing.assert_array_equal(short, long[long < total])
    assert shifted_exponential(np.random.default_rng(5), 3.0, 1.0, 0.0).size == 0
    assert np.diff(long).min() >= 1.0
