"""The only place that turns a seed into random generators (one Generator per run)."""

from __future__ import annotations

import numpy as np


def make_rng(seed: int) -> np.random.Generator:
    """The run's generator, derived from ``seed`` through :class:`numpy.random.SeedSequence`."""
    return np.random.default_rng(np.random.SeedSequence(seed))


def spawn_seeds(seed: int, n: int) -> list[int]:
    """``n`` independent child seeds of ``seed`` (for replicate runs), reproducible."""
    children = np.random.SeedSequence(seed).spawn(n)
    return [int(c.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1)) for c in children]
