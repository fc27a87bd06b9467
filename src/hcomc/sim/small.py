"""Kernels for the small arrays of one simulation step.

A step handles tens to thousands of entries; numba's versions of ``np.argsort``,
``np.flatnonzero``, ``np.searchsorted``, ``np.unique`` and ``np.concatenate`` carry a fixed
cost of microseconds per call, more than the arithmetic of a whole step of a small scene.
These loops give the same results (the sort is stable, as numpy's ``kind="stable"``).
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel

_RUN = 24  # entries sorted by insertion before merging


@kernel
def stable_argsort(keys: np.ndarray) -> np.ndarray:
    """Indices that sort ``keys`` ascending, equal keys in their original order."""
    n = keys.size
    order = np.arange(n)
    for start in range(0, n, _RUN):  # insertion sort of each run
        end = min(start + _RUN, n)
        for i in range(start + 1, end):
            item = order[i]
            j = i - 1
            while j >= start and keys[order[j]] > keys[item]:
                order[j + 1] = order[j]
                j -= 1
            order[j + 1] = item
    buffer = np.empty(n, dtype=np.int64)
    width = _RUN
    while width < n:  # bottom-up merges; the left run wins ties (stable)
        for lo in range(0, n, 2 * width):
            mid, hi = min(lo + width, n), min(lo + 2 * width, n)
            i, j, k = lo, mid, lo
            while i < mid and j < hi:
                if keys[order[j]] < keys[order[i]]:
                    buffer[k] = order[j]
                    j += 1
                else:
                    buffer[k] = order[i]
                    i += 1
                k += 1
            while i < mid:
                buffer[k] = order[i]
                i += 1
                k += 1
            while j < hi:
                buffer[k] = order[j]
                j += 1
                k += 1
        order, buffer = buffer, order
        width *= 2
    return order


@kernel
def nonzero(mask: np.ndarray) -> np.ndarray:
    """Indices where ``mask`` is true (``np.flatnonzero`` of a 1-D array)."""
    count = 0
    for k in range(mask.size):
        count += mask[k]
    out = np.empty(count, dtype=np.int64)
    m = 0
    for k in range(mask.size):
        if mask[k]:
            out[m] = k
            m += 1
    return out


@kernel(inline="always")
def search_right(sorted_keys: np.ndarray, value: float) -> int:
    """``np.searchsorted(sorted_keys, value, side="right")``."""
    lo, hi = 0, sorted_keys.size
    while lo < hi:
        mid = (lo + hi) // 2
        if value < sorted_keys[mid]:
            hi = mid
        else:
            lo = mid + 1
    return lo


@kernel(inline="always")
def search_left(sorted_keys: np.ndarray, value: float) -> int:
    """``np.searchsorted(sorted_keys, value, side="left")``."""
    lo, hi = 0, sorted_keys.size
    while lo < hi:
        mid = (lo + hi) // 2
        if sorted_keys[mid] < value:
            lo = mid + 1
        else:
            hi = mid
    return lo


@kernel
def unique(values: np.ndarray) -> np.ndarray:
    """Sorted distinct values (``np.unique`` of a 1-D array)."""
    if values.size == 0:
        return values.copy()
    ordered = values[stable_argsort(values)]
    keep = np.ones(ordered.size, dtype=np.bool_)
    for k in range(1, ordered.size):
        keep[k] = ordered[k] != ordered[k - 1]
    return ordered[nonzero(keep)]


@kernel
def join(parts: tuple[np.ndarray, ...]) -> np.ndarray:
    """The 1-D arrays of ``parts`` one after the other (``np.concatenate``)."""
    n = 0
    for p in parts:
        n += p.size
    out = np.empty(n, dtype=parts[0].dtype)
    m = 0
    for p in parts:
        out[m : m + p.size] = p
        m += p.size
    return out
