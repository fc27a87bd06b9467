"""numpy's summation of float64 runs, compiled: the same rounding as ``np.sum``.

numpy adds a contiguous run of float64 values by pairwise summation: runs of fewer than 8
terms from 0 in order, runs of up to 128 in 8 interleaved partial sums combined pairwise and
then the rest in order, longer runs split in two at a multiple of 8. Kernels that must round
as whole-array numpy code does sum with :func:`pairwise_sum`: the merge prediction's U_fuel
(:mod:`hcomc.control.prediction.fuel`, equal bit for bit to ``ndarray.sum`` over the same
samples) and PSO's adaptation (:mod:`hcomc.optim.pso.adaptation`, rounding as pymoo's numpy
does wherever numpy's float64 summation is this pairwise one; the tests check it is here).
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray

__all__ = ["pairwise_sum"]


@kernel
def _block_sum(a: FloatArray, start: int, n: int) -> float:
    """numpy's sum of a run of at most 128 terms: fewer than 8 from 0 in order, else 8
    interleaved partial sums combined pairwise, then the rest in order."""
    if n < 8:
        total = 0.0
        for i in range(start, start + n):
            total += a[i]
        return total
    r0, r1, r2, r3 = a[start], a[start + 1], a[start + 2], a[start + 3]
    r4, r5, r6, r7 = a[start + 4], a[start + 5], a[start + 6], a[start + 7]
    i = start + 8
    while i < start + n - n % 8:
        r0, r1, r2, r3 = r0 + a[i], r1 + a[i + 1], r2 + a[i + 2], r3 + a[i + 3]
        r4, r5, r6, r7 = r4 + a[i + 4], r5 + a[i + 5], r6 + a[i + 6], r7 + a[i + 7]
        i += 8
    total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    for k in range(i, start + n):
        total += a[k]
    return total


@kernel
def pairwise_sum(a: FloatArray, start: int, n: int) -> float:
    """The sum of ``a[start:start + n]`` as numpy sums a contiguous float64 run (``np.sum``,
    ``ndarray.sum(axis=-1)``): numpy's pairwise summation, the same rounding. Runs of up to
    128 terms are summed as :func:`_block_sum` does; longer runs are split in two at a
    multiple of 8 and the halves' sums added. The halving tree is walked with an explicit
    stack (left half first), since numba's disk cache does not keep recursive functions."""
    if n <= 128:
        return _block_sum(a, start, n)
    depth = 2 * (64 - 7)  # each split at least halves the run
    task_start = np.empty(2 * depth, dtype=np.int64)
    task_n = np.empty(2 * depth, dtype=np.int64)  # -1: add the two sums on top of `sums`
    sums = np.empty(depth)
    tasks, top = 1, 0
    task_start[0], task_n[0] = start, n
    while tasks > 0:
        tasks -= 1
        s, m = task_start[tasks], task_n[tasks]
        if m < 0:
            top -= 1
            sums[top - 1] = sums[top - 1] + sums[top]
        elif m <= 128:
            sums[top] = _block_sum(a, s, m)
            top += 1
        else:
            half = m // 2
            half -= half % 8
            task_start[tasks], task_n[tasks] = 0, -1  # popped last: left + right
            task_start[tasks + 1], task_n[tasks + 1] = s + half, m - half
            task_start[tasks + 2], task_n[tasks + 2] = s, half  # popped first
            tasks += 3
    return sums[0]
