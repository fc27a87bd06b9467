"""The only place that turns a seed into random generators (one Generator per run)."""

from __future__ import annotations

import numpy as np


def make_rng(seed: int) -> np.random.Generator:
    """The run's generator, derived from ``seed`` through :class:`numpy.random.SeedSequence`."""
    return np.random.default_rng(np.random.SeedSequence(seed))


SEED_HIGH = 2**31 - 1
"""Exclusive upper bound of the integer seeds :func:`draw_seed` draws."""


def draw_seed(rng: np.random.Generator) -> int:
    """One integer seed in ``[0, 2**31 - 1)`` drawn from ``rng`` (for a third-party
    optimiser, or the next episode of an environment)."""
    return int(rng.integers(SEED_HIGH))


def spawn_seeds(seed: int, n: int) -> list[int]:
    """``n`` independent child seeds of ``seed`` (for replicate runs), reproducible."""
    children = np.random.SeedSequence(seed).spawn(n)
    return [int(c.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1)) for c in children]
