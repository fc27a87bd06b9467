"""The moves of generalized simulated annealing, compiled: SciPy's visiting steps.

The kernels of :class:`hcomc.optim.sa.CompiledAnnealingOptimizer`: a Cauchy-Lorentz-like
visiting step per variable, limited to +-1e8 and wrapped into the search box as SciPy's
``dual_annealing`` does (Tsallis and Stariolo 1996; Xiang et al. 1997). ``fmod`` and the four
operations are exact or correctly rounded; ``exp`` and ``log`` are the C library's.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray

TAIL_LIMIT = 1.0e8  # SciPy's bound on a visiting step; larger steps are re-drawn below it
MIN_VISIT_BOUND = 1.0e-10  # a coordinate this close to its lower bound is moved off it


@kernel
def _wrap(x: float, lower: float, span: float) -> float:
    """A coordinate moved back into ``[lower, lower + span)`` modulo ``span`` and off the lower
    bound, with SciPy's operations (``fmod`` is exact, so any implementation agrees)."""
    b = np.fmod(x - lower, span) + span
    out = np.fmod(b, span) + lower
    if abs(out - lower) < MIN_VISIT_BOUND:
        out += MIN_VISIT_BOUND
    return out


@kernel  # x / 0 is inf, as in numpy
def move_all(
    x: FloatArray,
    xy: FloatArray,
    samples: FloatArray,
    sigma: float,
    visit: float,
    box: FloatArray,
    out: FloatArray,
) -> None:
    """SciPy's move of every variable, into ``out``: steps ``xy[:, 0] sigma / den`` with
    ``den = exp((qv - 1) log|xy[:, 1]| / (3 - qv))`` (the C library's ``exp`` and ``log``),
    steps beyond +-1e8 replaced by ``1e8 samples[0]`` or ``-1e8 samples[1]``, added to ``x``
    and wrapped into the box (``box`` = lower, span)."""
    above, below = TAIL_LIMIT * samples[0], -TAIL_LIMIT * samples[1]
    for k in range(x.size):
        d = math.exp((visit - 1.0) * math.log(abs(xy[k, 1])) / (3.0 - visit))
        step = xy[k, 0] * sigma / d
        if step > TAIL_LIMIT:
            step = above
        elif step < -TAIL_LIMIT:
            step = below
        out[k] = _wrap(step + x[k], box[0, k], box[1, k])


@kernel
def move_one(x: FloatArray, k: int, step: float, box: FloatArray, out: FloatArray) -> None:
    """SciPy's move of variable ``k`` alone by ``step`` (already limited), into ``out``."""
    out[:] = x
    out[k] = _wrap(step + x[k], box[0, k], box[1, k])
