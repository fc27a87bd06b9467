"""SBX crossover and polynomial mutation for the compiled NSGA-II, with pymoo's exact values.

The arithmetic runs in numba kernels; every power goes through numpy's ``np.power`` on
contiguous arrays, because numpy's vectorised ``pow`` and the C library's (which compiled code
calls) differ in the last bit on some inputs, and pymoo uses numpy's. Random numbers come from
the caller's generator in the order pymoo draws them. With the same generator state these
operators therefore return pymoo's ``SBX`` and ``PM`` offspring bit for bit (tests check it
through whole runs).
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit

from hcomc._typing import BoolArray, FloatArray

_PROB_VAR = 0.5  # SBX: probability that a variable of a crossed mating is crossed
_PROB_BIN = 0.5  # SBX: probability of exchanging the two children's values of a variable
_TOO_CLOSE = 1.0e-14  # SBX: parents closer than this in a variable are not crossed there


def _pow(base: FloatArray, exponent: float) -> FloatArray:
    """numpy's power of a contiguous array with a contiguous exponent array (pymoo's layout)."""
    with np.errstate(all="ignore"):
        out: FloatArray = np.power(base, np.full(base.size, exponent))
    return out


@njit(cache=True)
def _clamp(v: float, lo: float, hi: float) -> float:
    """``v`` within [lo, hi] (NaN stays NaN, as in pymoo's repairs)."""
    v = lo if v < lo else v
    return hi if v > hi else v


@njit(cache=True, error_model="numpy")
def _sbx_bases(
    X: FloatArray, xl: FloatArray, xu: FloatArray, u_cross: FloatArray
) -> tuple[BoolArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Crossed variables, their parent values and bounds, and the spread factors ``beta``
    towards the lower (first half) and upper bound (second half)."""
    _, n_matings, n_var = X.shape
    cross = u_cross < _PROB_VAR
    m = 0
    for i in range(n_matings):
        for j in range(n_var):
            if abs(X[0, i, j] - X[1, i, j]) <= _TOO_CLOSE or xl[j] == xu[j]:
                cross[i, j] = False
            if cross[i, j]:
                m += 1
    p1, p2, lo, hi = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    k = 0
    for i in range(n_matings):
        for j in range(n_var):
            if cross[i, j]:
                p1[k], p2[k], lo[k], hi[k] = X[0, i, j], X[1, i, j], xl[j], xu[j]
                k += 1
    beta = np.empty(2 * m)
    for k in range(m):
        y1, y2 = (p1[k], p2[k]) if p1[k] < p2[k] else (p2[k], p1[k])
        delta = y2 - y1
        beta[k] = 1.0 + (2.0 * (y1 - lo[k]) / delta)
        beta[m + k] = 1.0 + (2.0 * (hi[k] - y2) / delta)
    return cross, p1, p2, lo, hi, beta


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
def _sbx_children(
    X: FloatArray,
    xl: FloatArray,
    xu: FloatArray,
    cross: BoolArray,
    crossed_mating: BoolArray,
    p1: FloatArray,
    p2: FloatArray,
    alpha: FloatArray,
    rand: FloatArray,
    q_low: FloatArray,
    q_high: FloatArray,
    exchange: FloatArray,
) -> FloatArray:
    """The two children of every mating, (2 * n_matings, n_var): first children, then second."""
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


def sbx(
    X: FloatArray,
    xl: FloatArray,
    xu: FloatArray,
    eta: float,
    prob: float,
    rng: np.random.Generator,
) -> FloatArray:
    """Simulated binary crossover of parent pairs ``X`` (2, n_matings, n_var) -> children
    (2 n_matings, n_var): all first children, then all second children (pymoo's ``SBX``).

    A mating is crossed with probability ``prob``, each of its variables with probability 1/2
    (not when the parents are within 1e-14 or the bounds coincide); the two children's values of
    a crossed variable are exchanged with probability 1/2; children are clamped to the bounds.
    """
    _, n_matings, n_var = X.shape
    crossed_mating: BoolArray = np.asarray(rng.random(n_matings) < prob)
    if not np.any(crossed_mating):
        return np.ascontiguousarray(X.reshape(-1, n_var))
    rng.random((n_matings, 1))  # pymoo's draw for the exchange probability (1: unused)
    X = np.ascontiguousarray(X, dtype=np.float64)
    cross, p1, p2, _, _, beta = _sbx_bases(X, xl, xu, rng.random((n_matings, n_var)))
    rand = rng.random(p1.size)
    alpha, low, high = _sbx_alpha(_pow(beta, -(eta + 1.0)), rand)
    q_low, q_high = _pow(low, 1.0 / (eta + 1.0)), _pow(high, 1.0 / (eta + 1.0))
    exchange = rng.random(p1.size)
    return _sbx_children(
        X, xl, xu, cross, crossed_mating, p1, p2, alpha, rand, q_low, q_high, exchange
    )


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
def _pm_values(pw: FloatArray, rand: FloatArray) -> FloatArray:
    """The two candidate bases of the perturbation, towards the lower and the upper bound."""
    m = rand.size
    val = np.empty(2 * m)
    for k in range(m):
        r = rand[k]
        val[k] = 2.0 * r + (1.0 - 2.0 * r) * pw[k]
        val[m + k] = 2.0 * (1.0 - r) + 2.0 * (r - 0.5) * pw[m + k]
    return val


@njit(cache=True, error_model="numpy")
def _pm_apply(
    X: FloatArray,
    xl: FloatArray,
    xu: FloatArray,
    mut: BoolArray,
    x: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    rand: FloatArray,
    pv: FloatArray,
) -> FloatArray:
    n, n_var = X.shape
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
            out[i, j] = _clamp(out[i, j], xl[j], xu[j])
    return out


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
    n, n_var = X.shape
    X = np.ascontiguousarray(X, dtype=np.float64)
    mut = rng.random((n, n_var)) < min(0.5, 1.0 / n_var)
    x, lo, hi, xy = _pm_bases(X, xl, xu, mut)
    rand = rng.random(x.size)
    pv = _pow(_pm_values(_pow(xy, eta + 1.0), rand), 1.0 / (eta + 1.0))
    mutated = _pm_apply(X, xl, xu, mut, x, lo, hi, rand, pv)
    rows: BoolArray = np.asarray(rng.random(n) <= prob)
    return np.where(rows[:, None], mutated, X)


@functools.cache  # once per process
def warm_up() -> None:
    """Compile (or load from numba's cache) every kernel of this module now."""
    rng = np.random.default_rng(0)
    xl, xu = np.zeros(2), np.ones(2)
    children = sbx(rng.random((2, 2, 2)), xl, xu, 15.0, 1.0, rng)
    polynomial_mutation(children, xl, xu, 20.0, 1.0, rng)
