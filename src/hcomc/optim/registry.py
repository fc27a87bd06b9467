"""Optimisers by name (configs name a registered key: ``control.optimizer``)."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

from hcomc.config import ControlParams
from hcomc.optim.annealing import AnnealingOptimizer
from hcomc.optim.base import Optimizer
from hcomc.optim.nsga2 import CompiledNSGA2Optimizer
from hcomc.optim.pso.optimizer import CompiledPSOOptimizer
from hcomc.optim.pymoo_backend import NSGA2Optimizer, PSOOptimizer
from hcomc.optim.sa import CompiledAnnealingOptimizer

OPTIMIZERS: dict[str, Callable[..., Optimizer]] = {
    "nsga2": CompiledNSGA2Optimizer,  # "nsga2-pymoo"'s decisions, faster
    "nsga2-pymoo": NSGA2Optimizer,
    "pso": CompiledPSOOptimizer,  # "pso-pymoo"'s decisions, faster
    "pso-pymoo": PSOOptimizer,
    "sa": CompiledAnnealingOptimizer,  # "sa-scipy"'s decisions, faster
    "sa-scipy": AnnealingOptimizer,
}


def make_optimizer(name: str, **kwargs: Any) -> Optimizer:
    """The optimiser registered as ``name``, built with ``kwargs`` (e.g. ``pop_size=24``).

    Raises
    ------
    ValueError
        If ``name`` is not registered, or an option does not apply to it (e.g. ``pop_size``
        for SA, which has no population): nothing is silently ignored.
    """
    if name not in OPTIMIZERS:
        raise ValueError(f"unknown optimizer '{name}'; allowed: {', '.join(OPTIMIZERS)}")
    factory = OPTIMIZERS[name]
    known = set(inspect.signature(factory).parameters)
    unknown = sorted(set(kwargs) - known)
    if unknown:
        raise ValueError(
            f"option {', '.join(map(repr, unknown))} does not apply to optimizer '{name}'; "
            f"its options: {', '.join(sorted(known)) or 'none'}"
        )
    return factory(**kwargs)


def optimizer_from_config(control: ControlParams) -> Optimizer:
    """The optimiser ``control.optimizer`` with the config's options that apply to it."""
    options = {"pop_size": control.pop_size} if control.optimizer in POPULATION_BASED else {}
    return make_optimizer(control.optimizer, **options)


POPULATION_BASED = frozenset({"nsga2", "nsga2-pymoo", "pso", "pso-pymoo"})
"""Optimisers that take ``control.pop_size``."""
