"""SBX crossover and polynomial mutation for the compiled NSGA-II: pymoo's ``SBX`` and ``PM``.

Random numbers are drawn from the caller's generator in the order and sizes pymoo draws them;
the arithmetic runs in numba kernels, one call per operator, with pymoo's formulas in pymoo's
order of operations. A whole generation's offspring, draws included, is one compiled call
(:func:`offspring`: numba's ``Generator`` methods draw the numbers numpy's draw from the same
state), instead of pymoo's many numpy calls on small arrays.

Powers are the C library's ``pow`` (through numba), not numpy's ``np.power`` as in pymoo:
numpy picks its float64 power by the CPU at run time (SIMD versions on AVX-512 differ in the last
bit), the C library's is the same on every processor. Where the two differ, an offspring can
differ from pymoo's in the last bit; the tests hold the operators to pymoo's offspring within a
relative 1e-12 and whole runs to pymoo's solution quality.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray

_PROB_VAR = 0.5  # SBX: probability that a variable of a crossed mating is crossed
_PROB_BIN = 0.5  # SBX: probability of exchanging the two children's values of a variable
_TOO_CLOSE = 1.0e-14  # SBX: parents closer than this in a variable are not crossed there


class Bounds(NamedTuple):
    """The box of the decision variables, each (n_var,)."""

    lower: FloatArray
    upper: FloatArray


class SbxDraws(NamedTuple):
    """pymoo's ``SBX`` draws for parents (2, n_matings, n_var) and the crossed variables and
    bases they decide (:func:`_sbx_draws`); m is the number of crossed variables."""

    crossed_mating: BoolArray  # (n_matings,) the mating is crossed
    cross: BoolArray  # (n_matings, n_var) the variable is crossed
    p1: FloatArray  # (m,) the first parent's values of the crossed variables
    p2: FloatArray  # (m,) the second parent's
    beta: FloatArray  # (2 m,) spread factors towards the lower, then the upper bound
    rand: FloatArray  # (m,) uniform draws of the spread
    exchange: FloatArray  # (m,) uniform draws of the exchange of the children's values


class PmDraws(NamedTuple):
    """pymoo's ``PM`` draws for n rows (:func:`_pm_draws`)."""

    mut: BoolArray  # (n, n_var) the variable is mutated
    rand: FloatArray  # (m,) one uniform draw per mutated variable (bounds apart)
    rows: BoolArray  # (n,) the row keeps its mutation


@kernel  # numpy's error model: 0 ** -1 is inf, as in numpy's power
def _power(base: FloatArray, exponent: float) -> FloatArray:
    """``base ** exponent`` elementwise, with the C library's ``pow``."""
    out = np.empty(base.size)
    for k in range(base.size):
        out[k] = base[k] ** exponent
    return out


@kernel
def _clamp(v: float, lo: float, hi: float) -> float:
    """``v`` within [lo, hi] (NaN stays NaN, as in pymoo's repairs)."""
    v = lo if v < lo else v
    return hi if v > hi else v


@kernel
def _sbx_bases(
    X: FloatArray, xl: FloatArray, xu: FloatArray, u_cross: FloatArray
) -> tuple[BoolArray, FloatArray, FloatArray, FloatArray]:
    """Crossed variables, their parent values, and the spread factors ``beta`` towards the lower
    (first half) and upper bound (second half)."""
    _, n_matings, n_var = X.shape
    cross = u_cross < _PROB_VAR
    m = 0
    for i in range(n_matings):
        for j in range(n_var):
            if abs(X[0, i, j] - X[1, i, j]) <= _TOO_CLOSE or xl[j] == xu[j]:
                cross[i, j] = False
            if cross[i, j]:
                m += 1
    p1, p2, beta = np.empty(m), np.empty(m), np.empty(2 * m)
    k = 0
    for i in range(n_matings):
        for j in range(n_var):
            if cross[i, j]:
                p1[k], p2[k] = X[0, i, j], X[1, i, j]
                y1, y2 = (p1[k], p2[k]) if p1[k] < p2[k] else (p2[k], p1[k])
                delta = y2 - y1
                beta[k] = 1.0 + (2.0 * (y1 - xl[j]) / delta)
                beta[m + k] = 1.0 + (2.0 * (xu[j] - y2) / delta)
                k += 1
    return cross, p1, p2, beta


@kernel
def _sbx_alpha(pw: FloatArray, rand: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``alpha = 2 - beta^-(eta+1)`` and the two candidate bases of ``beta_q``."""
    m = rand.size
    alpha = 2.0 - pw
    low, high = np.empty(2 * m), np.empty(2 * m)
    for k in range(2 * m):
        r = rand[k % m]
        low[k] = r * alpha[k]
        high[k] = 1.0 / (2.0 - r * alpha[k])
    return alpha, low, high


@kernel
def _sbx_children(
    X: FloatArray,
    bounds: Bounds,
    draws: SbxDraws,
    alpha: FloatArray,
    q_low: FloatArray,
    q_high: FloatArray,
) -> FloatArray:
    """The two children of every mating, (2 * n_matings, n_var): first children, then second."""
    xl, xu = bounds
    crossed_mating, cross, p1, p2, _, rand, exchange = draws
    _, n_matings, n_var = X.shape
    m = rand.size
    Q = X.copy()
    k = 0
    for i in range(n_matings):
        for j in range(n_var):
            if not cross[i, j]:
                continue
            betaq = np.zeros(2)
            for side in range(2):
                idx = side * m + k
                inv = 1.0 / alpha[idx]
                if rand[k] <= inv:
                    betaq[side] = q_low[idx]
                elif rand[k] > inv:
                    betaq[side] = q_high[idx]
            smaller = p1[k] < p2[k]
            y1, y2 = (p1[k], p2[k]) if smaller else (p2[k], p1[k])
            delta = y2 - y1
            c1 = 0.5 * ((y1 + y2) - betaq[0] * delta)
            c2 = 0.5 * ((y1 + y2) + betaq[1] * delta)
            child1, child2 = (c1, c2) if smaller else (c2, c1)
            if (exchange[k] < _PROB_BIN) != (p1[k] > p2[k]):
                child1, child2 = child2, child1
            Q[0, i, j], Q[1, i, j] = child1, child2
            k += 1
    out = np.empty((2 * n_matings, n_var))
    for c in range(2):
        for i in range(n_matings):
            for j in range(n_var):
                v = _clamp(Q[c, i, j], xl[j], xu[j]) if crossed_mating[i] else X[c, i, j]
                out[c * n_matings + i, j] = v
    return out


@kernel
def _sbx(X: FloatArray, bounds: Bounds, draws: SbxDraws, eta: float) -> FloatArray:
    """SBX children (2 * n_matings, n_var) of parents ``X`` from the bases and ``draws``
    with distribution index ``eta``; the parents themselves when no mating is crossed."""
    if not draws.crossed_mating.any():
        return X.copy().reshape(-1, X.shape[2])
    alpha, low, high = _sbx_alpha(_power(draws.beta, -(eta + 1.0)), draws.rand)
    q_low = _power(low, 1.0 / (eta + 1.0))
    q_high = _power(high, 1.0 / (eta + 1.0))
    return _sbx_children(X, bounds, draws, alpha, q_low, q_high)


@kernel
def _sbx_draws(X: FloatArray, bounds: Bounds, prob: float, rng: np.random.Generator) -> SbxDraws:
    """pymoo's ``SBX`` draws for parents ``X`` (2, n_matings, n_var), in its order, with the
    crossed variables and bases they decide: crossed matings (probability ``prob``), then only
    if any is crossed: the exchange probability (1: unused), crossed variables, ``rand`` and the
    exchange of crossed values."""
    _, n_matings, n_var = X.shape
    crossed_mating: BoolArray = np.asarray(rng.random(n_matings) < prob)
    if not crossed_mating.any():
        none = np.empty(0)
        cross = np.zeros((n_matings, n_var), np.bool_)
        return SbxDraws(crossed_mating, cross, none, none, none, none, none)
    rng.random((n_matings, 1))  # pymoo's draw for the exchange probability (1: unused)
    cross, p1, p2, beta = _sbx_bases(X, bounds.lower, bounds.upper, rng.random((n_matings, n_var)))
    rand = rng.random(p1.size)
    return SbxDraws(crossed_mating, cross, p1, p2, beta, rand, rng.random(p1.size))


@kernel
def _pm_bases(
    X: FloatArray, xl: FloatArray, xu: FloatArray, mut: BoolArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Mutated values with their bounds, and ``1 - delta`` to the lower (first half) and upper
    bound (second half)."""
    n, n_var = X.shape
    m = 0
    for i in range(n):
        for j in range(n_var):
            if xl[j] == xu[j]:
                mut[i, j] = False
            if mut[i, j]:
                m += 1
    x, lo, hi = np.empty(m), np.empty(m), np.empty(m)
    xy = np.empty(2 * m)
    k = 0
    for i in range(n):
        for j in range(n_var):
            if mut[i, j]:
                x[k], lo[k], hi[k] = X[i, j], xl[j], xu[j]
                xy[k] = 1.0 - (x[k] - lo[k]) / (hi[k] - lo[k])
                xy[m + k] = 1.0 - (hi[k] - x[k]) / (hi[k] - lo[k])
                k += 1
    return x, lo, hi, xy


@kernel
def _pm_values(pw: FloatArray, rand: FloatArray) -> FloatArray:
    """The two candidate bases of the perturbation, towards the lower and the upper bound."""
    m = rand.size
    val = np.empty(2 * m)
    for k in range(m):
        r = rand[k]
        val[k] = 2.0 * r + (1.0 - 2.0 * r) * pw[k]
        val[m + k] = 2.0 * (1.0 - r) + 2.0 * (r - 0.5) * pw[m + k]
    return val


@kernel
def _pm(X: FloatArray, bounds: Bounds, draws: PmDraws, eta: float) -> FloatArray:
    """Polynomial mutation of rows ``X`` with distribution index ``eta``: the variables
    ``draws.mut``, kept in the rows ``draws.rows``."""
    xl, xu = bounds
    mut, rand, rows = draws
    n, n_var = X.shape
    x, lo, hi, xy = _pm_bases(X, xl, xu, mut)
    pv = _power(_pm_values(_power(xy, eta + 1.0), rand), 1.0 / (eta + 1.0))
    m = rand.size
    out = X.copy()
    k = 0
    for i in range(n):
        for j in range(n_var):
            if not mut[i, j]:
                continue
            dq = pv[k] - 1.0 if rand[k] <= 0.5 else 1.0 - pv[m + k]
            out[i, j] = _clamp(x[k] + dq * (hi[k] - lo[k]), lo[k], hi[k])
            k += 1
    for i in range(n):
        for j in range(n_var):
            out[i, j] = _clamp(out[i, j], xl[j], xu[j]) if rows[i] else X[i, j]
    return out


@kernel
def _pm_draws(n: int, bounds: Bounds, prob: float, rng: np.random.Generator) -> PmDraws:
    """pymoo's ``PM`` draws for ``n`` rows, in its order: mutated variables (probability
    ``min(0.5, 1 / n_var)``, none where the bounds coincide), one number per mutated variable,
    and the rows kept mutated (probability ``prob``)."""
    xl, xu = bounds
    n_var = xl.size
    mut = rng.random((n, n_var)) < min(0.5, 1.0 / n_var)
    m = 0
    for i in range(n):
        for j in range(n_var):
            m += 1 if mut[i, j] and xl[j] != xu[j] else 0
    rand = rng.random(m)
    return PmDraws(mut, rand, rng.random(n) <= prob)


def polynomial_mutation(
    X: FloatArray,
    xl: FloatArray,
    xu: FloatArray,
    eta: float,
    prob: float,
    rng: np.random.Generator,
) -> FloatArray:
    """Polynomial mutation (pymoo's ``PM``): each row with probability ``prob``, each of its
    variables with probability ``min(0.5, 1 / n_var)`` (not where the bounds coincide), within
    the bounds."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    return _drawn_mutation(X, Bounds(xl, xu), float(eta), float(prob), rng)


@kernel
def _drawn_mutation(
    X: FloatArray, bounds: Bounds, eta: float, prob: float, rng: np.random.Generator
) -> FloatArray:
    """:func:`polynomial_mutation` compiled, its draws included."""
    return _pm(X, bounds, _pm_draws(X.shape[0], bounds, prob, rng), eta)


@kernel
def _offspring(
    X: FloatArray,
    bounds: Bounds,
    crossover: SbxDraws,
    crossover_eta: float,
    mutation: PmDraws,
    mutation_eta: float,
) -> FloatArray:
    """SBX children of parents ``X``, then their polynomial mutation, in one call
    (``*_eta``: the operators' distribution indices)."""
    children = _sbx(X, bounds, crossover, crossover_eta)
    return _pm(children, bounds, mutation, mutation_eta)


def offspring(
    X: FloatArray,
    xl: FloatArray,
    xu: FloatArray,
    crossover: tuple[float, float],
    mutation: tuple[float, float],
    rng: np.random.Generator,
) -> FloatArray:
    """Offspring (2 n_matings, n_var) of parent pairs ``X`` (2, n_matings, n_var): simulated
    binary crossover (pymoo's ``SBX``), all first children then all second children, each then
    mutated (pymoo's ``PM``); ``crossover`` and ``mutation`` are (eta, probability).

    A mating is crossed with probability ``prob``, each of its variables with probability 1/2
    (not when the parents are within 1e-14 or the bounds coincide); the two children's values of
    a crossed variable are exchanged with probability 1/2; children are clamped to the bounds.
    Mutation is that of :func:`polynomial_mutation`. One compiled call
    (:func:`drawn_offspring`), the draws included.
    """
    X = np.ascontiguousarray(X, dtype=np.float64)
    return drawn_offspring(X, Bounds(xl, xu), float(crossover[0]), float(crossover[1]),
                           float(mutation[0]), float(mutation[1]), rng)  # fmt: skip


@kernel
def drawn_offspring(
    X: FloatArray, bounds: Bounds, crossover_eta: float, crossover_prob: float,
    mutation_eta: float, mutation_prob: float, rng: np.random.Generator,
) -> FloatArray:  # fmt: skip
    """:func:`offspring` compiled: the SBX draws, then the PM draws, from ``rng``
    (:func:`_sbx_draws`, :func:`_pm_draws`), then :func:`_offspring`."""
    sbx = _sbx_draws(X, bounds, crossover_prob, rng)
    pm = _pm_draws(2 * X.shape[1], bounds, mutation_prob, rng)
    return _offspring(X, bounds, sbx, crossover_eta, pm, mutation_eta)


@functools.cache  # once per process
def warm_up() -> None:
    """Compile (or load from numba's cache) every kernel of this module now."""
    rng = np.random.default_rng(0)
    xl, xu = np.zeros(2), np.ones(2)
    children = offspring(rng.random((2, 2, 2)), xl, xu, (15.0, 1.0), (20.0, 1.0), rng)
    polynomial_mutation(children, xl, xu, 20.0, 1.0, rng)
