"""Ensembles reproduce runs alone, bit for bit, and the step's typed-list cache follows its keys.

The engine's recorded runs are checked in ``tests/scenario/test_recorded_runs.py``.
"""

from __future__ import annotations

import numpy as np

from hcomc.sim.engine import Simulation


def test_an_ensemble_gives_each_run_bit_identical_results() -> None:
    """Six runs (three conditions, FIFO and no controller, HCOMC included, and a corridor's
    first four minutes with its five ramps) advanced as one batch on 1 and 2 threads equal the
    same runs simulated alone, key groups included."""
    from hcomc.config import load_config
    from hcomc.corridor.loading import load_corridor
    from hcomc.sim.corridor_scene import corridor_config, corridor_scene
    from hcomc.sim.ensemble import run_ensemble

    corridor = load_corridor("corridor", {"corridor.duration": 240.0})

    def runs() -> list[Simulation]:
        return [
            Simulation(load_config("C2", duration=40.0), 1),
            Simulation(load_config("C5", duration=40.0, control={"controller": "fifo"}), 2),
            Simulation(load_config("C1", duration=40.0, control={"controller": "hcomc"}), 3),
            Simulation(load_config("C3", duration=40.0), 4),
            Simulation(load_config("C4", duration=40.0, demand={"ramp": "flow"}), 5),
            Simulation(corridor_config(corridor), 6, scene=corridor_scene(corridor)),
        ]

    alone = [sim.run() for sim in runs()]
    for threads in (1, 2):
        together = run_ensemble(runs(), threads=threads)
        for a, b in zip(alone, together, strict=True):
            for name in ("x", "y", "v", "a", "lane", "active"):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
            np.testing.assert_array_equal(
                np.asarray(a.events.tolist()), np.asarray(b.events.tolist())
            )
            assert a.meta.get("key_groups") == b.meta.get("key_groups")
        assert len(together[-1].meta["key_groups"]) > 20  # the corridor's ramps


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
