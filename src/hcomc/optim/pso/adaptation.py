"""PSO's fuzzy adaptation of ``w``, ``c1`` and ``c2`` from the swarm's spread (pymoo's
``PSO._adapt``).

:func:`swarm_spread` measures how the personal bests spread and where the social best lies
among them in one compiled pass; :func:`adapt` turns that into the evolutionary factor, its
dominant fuzzy state and the new weights, so that
:class:`~hcomc.optim.pso.optimizer.CompiledPSOOptimizer` adapts as pymoo's ``PSO`` does (see
:mod:`hcomc.optim.pso.optimizer`). Sums are plain sums in index order and ``w``'s ``exp`` is the
C library's: the values depend on neither numpy's summation order nor its CPU-dispatched
``exp``.
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.optim.ieee import exp

__all__ = ["adapt", "swarm_spread"]


@kernel(inline="always")  # called n^2 times per spread: no call with array arguments
def _distance(p: FloatArray, q: FloatArray, width: FloatArray) -> float:
    """Box-normalised euclidean distance of two rows, its squared terms summed in variable
    order."""
    total = 0.0
    for k in range(p.size):
        d = (p[k] - q[k]) / width[k]
        total += d * d
    return float(np.sqrt(total))


@kernel
def _spread_kernel(
    P_X: FloatArray, s_x: FloatArray, xl: FloatArray, xu: FloatArray
) -> tuple[FloatArray, float]:
    """:func:`swarm_spread` compiled."""
    n = P_X.shape[0]
    width = xu - xl
    D, mD = np.empty((n, n)), np.empty(n)
    for i in range(n):
        D[i, i] = _distance(P_X[i], P_X[i], width)
        for j in range(i + 1, n):
            # a - b is exactly -(b - a): the distance matrix is symmetric
            d = _distance(P_X[i], P_X[j], width)
            D[i, j], D[j, i] = d, d
    for i in range(n):
        total = 0.0
        for j in range(n):
            total += D[i, j]
        mD[i] = total / (n - 1)
    social = 0.0
    for j in range(n):
        social += _distance(s_x, P_X[j], width)
    return mD, social / n


def swarm_spread(
    P_X: FloatArray, s_x: FloatArray, xl: FloatArray, xu: FloatArray
) -> tuple[FloatArray, float]:
    """pymoo's two spreads of ``PSO._adapt`` (box-normalised euclidean distances): each
    personal best's mean distance to all personal bests (itself included, divided by n - 1)
    and the mean distance of the social best ``s_x`` to them. One compiled pass, plain sums.
    """
    mD, g_D = _spread_kernel(P_X, s_x, xl, xu)
    return mD, float(g_D)


def _memberships(f: float) -> list[float]:
    """Fuzzy memberships of the evolutionary factor ``f`` in the four states (exploration,
    exploitation, convergence, jumping out), pymoo's piecewise-linear functions."""
    s1 = 0 if f <= 0.4 else 5 * f - 2 if f <= 0.6 else 1 if f <= 0.7 else -10 * f + 8
    s1 = 0 if f > 0.8 else s1
    s2 = 0 if f <= 0.2 else 10 * f - 2 if f <= 0.3 else 1 if f <= 0.4 else -5 * f + 3
    s2 = 0 if f > 0.6 else s2
    s3 = 1 if f <= 0.1 else -5 * f + 1.5 if f <= 0.3 else 0
    s4 = 0 if f <= 0.7 else 5 * f - 3.5 if f <= 0.9 else 1
    return [s1, s2, s3, s4]


def adapt(
    P_X: FloatArray,
    s_x: FloatArray,
    c1: float,
    c2: float,
    xl: FloatArray,
    xu: FloatArray,
    rng: np.random.Generator,
) -> tuple[float, float, float]:
    """New ``(w, c1, c2)`` from the personal bests' spread (pymoo's ``PSO._adapt``).

    The evolutionary factor ``f`` places the mean distance of the social best ``s_x`` (the one
    this generation moved towards) to the personal bests among the particles' mean distances;
    its dominant fuzzy state shifts ``c1``/``c2`` by a random ``delta`` in [0.05, 0.1), clamped
    to [1.5, 2.5] and rescaled to a sum of at most 4 (``c2`` rescaled with the new ``c1``, as
    pymoo does), and ``w = 1 / (1 + 1.5 exp(-2.6 f))``.
    """
    mD, g_D = swarm_spread(P_X, s_x, xl, xu)
    lo, hi = float(mD.min()), float(mD.max())
    f = (g_D - lo) / (hi - lo + 1e-32)
    if np.isnan(f):  # pymoo fails here too (its memberships of NaN are None)
        raise ValueError(
            "adaptive PSO needs xl < xu in every variable (distances are box-normalised)"
        )
    strategy = int(np.array(_memberships(f)).argmax()) + 1
    delta = 0.05 + (rng.random() * 0.05)
    step = {1: (delta, -delta), 2: (0.5 * delta, -0.5 * delta),
            3: (0.5 * delta, 0.5 * delta), 4: (-delta, delta)}[strategy]  # fmt: skip
    c1, c2 = c1 + step[0], c2 + step[1]
    c1 = max(1.5, min(2.5, c1))
    c2 = max(1.5, min(2.5, c2))
    if c1 + c2 > 4.0:
        c1 = 4.0 * (c1 / (c1 + c2))
        c2 = 4.0 * (c2 / (c1 + c2))
    # f is of the order of 1e32 when all mean distances are equal: exp overflows to inf, w is 0
    w = 1.0 / (1.0 + 1.5 * exp(-2.6 * float(f)))
    return w, c1, c2
