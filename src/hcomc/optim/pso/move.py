"""PSO's move and its improvement replacement, compiled (pymoo's ``PSO._infill`` and
``_advance`` without its objects).

:func:`move` computes the next generation's velocities and positions with the velocity
equation, recomputes rows still outside the box with fresh random numbers and repairs what is
left, as pymoo does; :func:`improvement` says which new positions replace their personal
bests. Both draw the same random numbers as pymoo's code, in the same order, so that
:class:`~hcomc.optim.pso.optimizer.CompiledPSOOptimizer` runs pymoo's algorithm (see
:mod:`hcomc.optim.pso.optimizer`).
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray, IntArray

__all__ = ["MAX_VELOCITY_RATE", "improvement", "move"]

MAX_VELOCITY_RATE = 0.2  # |velocity| <= this share of the box, per variable (pymoo default)
_RETRIES = 20  # recomputations of rows still outside the box (pymoo's fixed count)


@kernel
def _equation(
    X: FloatArray,
    P_X: FloatArray,
    s_x: FloatArray,
    V: FloatArray,
    v_max: FloatArray,
    params: tuple[float, float, float],
    rows: IntArray,
    rng: np.random.Generator,
    Xp: FloatArray,
    Vp: FloatArray,
) -> None:
    """Rows ``rows`` of the new positions and velocities, in place: ``X + V'`` with
    ``V' = w V + c1 r1 (P - X) + c2 r2 (s - X)`` clamped to +-v_max (pymoo's ``pso_equation``
    then ``set_to_bounds_if_outside``: the same operations in the same order per element, and
    ``r1`` then ``r2`` drawn as (rows, n_var) arrays from the same generator)."""
    w, c1, c2 = params
    r1 = rng.random((rows.size, X.shape[1]))
    r2 = rng.random((rows.size, X.shape[1]))
    for a in range(rows.size):
        i = rows[a]
        for j in range(X.shape[1]):
            v = (
                w * V[i, j]
                + c1 * r1[a, j] * (P_X[i, j] - X[i, j])
                + c2 * r2[a, j] * (s_x[j] - X[i, j])
            )
            v = -v_max[j] if v < -v_max[j] else v
            v = v_max[j] if v > v_max[j] else v
            Vp[i, j] = v
            Xp[i, j] = X[i, j] + v


@kernel
def _outside(Xp: FloatArray, xl: FloatArray, xu: FloatArray) -> IntArray:
    """Rows with a variable outside the box, ascending (NaN is not outside)."""
    out = np.zeros(Xp.shape[0], dtype=np.bool_)
    for i in range(Xp.shape[0]):
        for j in range(Xp.shape[1]):
            if Xp[i, j] < xl[j] or Xp[i, j] > xu[j]:
                out[i] = True
    return np.flatnonzero(out)


@kernel
def move(
    X: FloatArray,
    P_X: FloatArray,
    s_x: FloatArray,
    V: FloatArray,
    params: tuple[float, float, float],
    xl: FloatArray,
    xu: FloatArray,
    rng: np.random.Generator,
) -> tuple[FloatArray, FloatArray, int]:
    """Positions and velocities of the next generation, inside the box (pymoo's ``_infill``
    before the perturbation of the best), and how many recomputation rounds it took.

    Rows outside the box are recomputed from the old position with new random numbers, at most
    20 times; a variable still outside is then drawn uniformly between its bound and its old
    position (``repair_random_init``), the velocity is kept. One compiled kernel: on the merge
    problem, whose best rows lie on bounds, a move takes about a dozen rounds, each a dozen
    small numpy calls in pymoo's form. numba's ``Generator.random`` reads the same bit
    generator as numpy's, so the draws are the same numbers.
    """
    n, n_var = X.shape
    v_max = MAX_VELOCITY_RATE * (xu - xl)
    Xp, Vp = np.empty((n, n_var)), np.empty((n, n_var))
    _equation(X, P_X, s_x, V, v_max, params, np.arange(n), rng, Xp, Vp)
    retries = 0
    while retries < _RETRIES:
        rows = _outside(Xp, xl, xu)
        if rows.size == 0:
            break
        _equation(X, P_X, s_x, V, v_max, params, rows, rng, Xp, Vp)
        retries += 1
    for side in range(2):  # below the box first, then above, each in row-major order
        count = 0
        for i in range(n):
            for j in range(n_var):
                count += Xp[i, j] < xl[j] if side == 0 else Xp[i, j] > xu[j]
        if count == 0:
            continue
        r = rng.random(count)
        k = 0
        for i in range(n):
            for j in range(n_var):
                if side == 0 and Xp[i, j] < xl[j]:
                    Xp[i, j] = xl[j] + r[k] * (X[i, j] - xl[j])
                    k += 1
                elif side == 1 and Xp[i, j] > xu[j]:
                    Xp[i, j] = xu[j] - r[k] * (xu[j] - X[i, j])
                    k += 1
    return Xp, Vp, retries


@kernel
def _same(a: FloatArray, b: FloatArray) -> bool:
    """Euclidean distance 0: every squared difference is 0 (a sum of non-negative numbers
    cannot round to 0 otherwise); NaN never is."""
    for k in range(a.size):
        d = a[k] - b[k]
        if d * d != 0.0:
            return False
    return True


@kernel
def improvement(X: FloatArray, F: FloatArray, P_X: FloatArray, P_F: FloatArray) -> BoolArray:
    """Particles whose new position replaces their personal best (pymoo's
    ``ImprovementReplacement`` without constraints): a strictly lower cost (never against or
    with a NaN), and the new position is no duplicate, i.e. at euclidean distance > 0 from
    every earlier new position and from every personal best (``DefaultDuplicateElimination
    (epsilon=0)``, which pymoo applies to the new positions against themselves, then against
    the personal bests)."""
    n = X.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        if not F[i] < P_F[i]:
            continue
        dup = False
        for j in range(i):
            dup = dup or _same(X[i], X[j])
        for j in range(P_X.shape[0]):
            dup = dup or _same(X[i], P_X[j])
        out[i] = not dup
    return out
