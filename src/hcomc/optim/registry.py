"""Optimisers by name (configs name a registered key: ``control.optimizer``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from hcomc.optim.annealing import AnnealingOptimizer
from hcomc.optim.base import Optimizer
from hcomc.optim.pymoo_backend import NSGA2Optimizer, PSOOptimizer

OPTIMIZERS: dict[str, Callable[..., Optimizer]] = {
    "nsga2": NSGA2Optimizer,
    "pso": PSOOptimizer,
    "sa": AnnealingOptimizer,
}


def make_optimizer(name: str, **kwargs: Any) -> Optimizer:
    """The optimiser registered as ``name``, built with ``kwargs`` (e.g. ``pop_size=24``).

    Raises
    ------
    ValueError
        If ``name`` is not registered.
    """
    if name not in OPTIMIZERS:
        raise ValueError(f"unknown optimizer '{name}'; allowed: {', '.join(OPTIMIZERS)}")
    return OPTIMIZERS[name](**kwargs)
