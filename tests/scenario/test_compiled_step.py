"""Ensembles reproduce runs alone, bit for bit, and the step's typed-list cache follows its keys.

The engine's recorded runs are checked in ``tests/scenario/test_recorded_runs.py``.
"""

from __future__ import annotations

import numpy as np

from hcomc.sim.engine import Simulation


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
    from hcomc.sim.typed_lists import TypedListCache

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
