"""The compiled step reproduces the numpy step it replaced, and ensembles reproduce runs alone.

The references in ``tests/data/numpy_step`` were recorded with the numpy implementation of
the step (``make_reference.py`` there): C1-C5 with no controller, C1-C4 with FIFO, C4 with a ramp
flow and the platoon scenario, seed 0 — FIFO's decisions included, so the Python/compiled
hand-over at decision events is covered too.

Observed: the logs (float32) and the event kinds and vehicles are identical; float64 positions
differ by at most one unit in the last place (2.3e-13 m at x = 1.5 km). The numpy step called
numpy's vectorised transcendental functions (SIMD implementations of pow, exp, tanh), the
compiled step calls the C library's scalar ones, which round differently in the last bit for
a few percent of arguments.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from hcomc.sim.engine import Simulation

DATA = Path(__file__).parent.parent / "data" / "numpy_step"
_spec = importlib.util.spec_from_file_location("make_reference", DATA / "make_reference.py")
assert _spec is not None
assert _spec.loader is not None
reference = importlib.util.module_from_spec(_spec)  # its CASES: what was recorded
_spec.loader.exec_module(reference)


@pytest.mark.parametrize("name", sorted(reference.CASES))
def test_compiled_step_reproduces_the_numpy_step(name: str) -> None:
    from hcomc.config import load_config

    preset, overrides = reference.CASES[name]
    ref = np.load(DATA / f"{name}.npz")
    sim = Simulation(load_config(preset, **overrides), 0)
    log = sim.run()
    # the float64 state after the whole run, within 1e-9 m
    np.testing.assert_allclose(sim.x, ref["x"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(sim.v, ref["v"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(sim.y, ref["y"], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(sim.lane, ref["lane"])
    np.testing.assert_array_equal(log.x[::10], ref["log_x"])
    np.testing.assert_array_equal(log.v[::10], ref["log_v"])
    events = np.asarray(log.events.tolist(), dtype=np.float64).reshape(-1, 6)
    np.testing.assert_array_equal(events[:, :4], ref["events"][:, :4])  # t, kind, vehicles
    np.testing.assert_allclose(events[:, 4:], ref["events"][:, 4:], rtol=0, atol=1e-9)


def test_an_ensemble_gives_each_run_bit_identical_results() -> None:
    """Five runs (two conditions, FIFO and no controller, HCOMC included) advanced as one
    batch on 1 and 2 threads equal the same runs simulated alone."""
    from hcomc.config import load_config
    from hcomc.sim.ensemble import run_ensemble

    def configs():
        return [
            (load_config("C2", duration=40.0), 1),
            (load_config("C5", duration=40.0, control={"controller": "fifo"}), 2),
            (load_config("C1", duration=40.0, control={"controller": "hcomc"}), 3),
            (load_config("C3", duration=40.0), 4),
            (load_config("C4", duration=40.0, demand={"ramp": "flow"}), 5),
        ]

    alone = [Simulation(c, s).run() for c, s in configs()]
    for threads in (1, 2):
        together = run_ensemble([Simulation(c, s) for c, s in configs()], threads=threads)
        for a, b in zip(alone, together, strict=True):
            for name in ("x", "y", "v", "a", "lane", "active"):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
            np.testing.assert_array_equal(
                np.asarray(a.events.tolist()), np.asarray(b.events.tolist())
            )


def test_typed_list_cache_follows_its_keys_as_they_change_grow_and_shrink() -> None:
    """Entry k of each list is always its column of key k; places whose key stayed are not
    converted again."""
    from hcomc.sim.ensemble import TypedListCache

    class Key:
        def __init__(self, value: float) -> None:
            self.value = value

    converted: list[float] = []

    def column(key: Key) -> float:
        converted.append(key.value)
        return key.value

    def twice(key: Key) -> float:
        return 2.0 * key.value

    keys = [Key(float(k)) for k in range(12)]
    cache = TypedListCache()
    rng = np.random.default_rng(0)
    for _ in range(30):
        size = int(rng.integers(1, 12))
        picked = [keys[k] for k in rng.choice(12, size=size, replace=False)]
        previous = list(cache._keys)
        converted.clear()
        values, doubled = cache.lists(picked, column, twice)
        assert list(values) == [k.value for k in picked]
        assert list(doubled) == [2.0 * k.value for k in picked]
        kept = sum(1 for k, key in enumerate(picked) if k < len(previous) and previous[k]() is key)
        assert len(converted) == (size if not previous else size - kept)
