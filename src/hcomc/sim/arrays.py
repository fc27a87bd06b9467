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
    return stable_argsort_into(keys, np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64))


@kernel
def stable_argsort_into(keys: np.ndarray, order: np.ndarray, buffer: np.ndarray) -> np.ndarray:
    """:func:`stable_argsort` in the caller's work arrays ``order`` and ``buffer`` (at least
    ``keys.size`` long each); returns the first ``keys.size`` entries of the one that holds
    the result."""
    n = keys.size
    order, buffer = order[:n], buffer[:n]
    for i in range(n):
        order[i] = i
    for start in range(0, n, _RUN):  # insertion sort of each run
        end = min(start + _RUN, n)
        for i in range(start + 1, end):
            item = order[i]
            j = i - 1
            while j >= start and keys[order[j]] > keys[item]:
                order[j + 1] = order[j]
                j -= 1
            order[j + 1] = item
    width = _RUN
    while width < n:  # bottom-up merges; the left run wins ties (stable)
        for lo in range(0, n, 2 * width):
            _merge_into(keys, order, buffer, lo, min(lo + width, n), min(lo + 2 * width, n))
        order, buffer = buffer, order
        width *= 2
    return order


@kernel
def sort_runs(keys: np.ndarray, order: np.ndarray, buffer: np.ndarray, lo: int, hi: int) -> None:
    """Sort ``order[lo:hi]`` stably by ``keys[order[...]]`` (ties keep their order), in place;
    ``buffer[lo:hi]`` is work space.

    A natural merge sort: strictly descending runs are reversed (their keys are distinct, so
    this keeps it stable), then adjacent ascending runs are merged, the left run winning
    ties. Linear in the length for input made of a few runs, as the entries of one lane
    are (vehicles in the order they entered: downstream first).
    """
    _reverse_descending_runs(keys, order, lo, hi)
    merged = True
    while merged:  # merge pairs of adjacent ascending runs until one is left
        merged = False
        i = lo
        while i < hi:
            mid = _run_end(keys, order, i, hi)
            if mid >= hi:
                break
            end = _run_end(keys, order, mid, hi)
            _merge(keys, order, buffer, i, mid, end)
            merged = True
            i = end


@kernel(inline="always")
def _reverse_descending_runs(keys: np.ndarray, order: np.ndarray, lo: int, hi: int) -> None:
    """Reverse each strictly descending run of ``order[lo:hi]``."""
    i = lo
    while i < hi - 1:
        j = i + 1
        if keys[order[j]] < keys[order[i]]:
            while j + 1 < hi and keys[order[j + 1]] < keys[order[j]]:
                j += 1
            a, b = i, j
            while a < b:
                order[a], order[b] = order[b], order[a]
                a += 1
                b -= 1
        else:
            while j + 1 < hi and keys[order[j + 1]] >= keys[order[j]]:
                j += 1
        i = j + 1


@kernel(inline="always")
def _run_end(keys: np.ndarray, order: np.ndarray, start: int, hi: int) -> int:
    """End of the ascending run of ``order`` that begins at ``start``."""
    end = start + 1
    while end < hi and keys[order[end]] >= keys[order[end - 1]]:
        end += 1
    return end


@kernel(inline="always")
def _merge(
    keys: np.ndarray, order: np.ndarray, buffer: np.ndarray, lo: int, mid: int, hi: int
) -> None:
    """Merge the ascending runs ``order[lo:mid]`` and ``order[mid:hi]`` in place (through
    ``buffer``), the left run winning ties."""
    _merge_into(keys, order, buffer, lo, mid, hi)
    for k in range(lo, hi):
        order[k] = buffer[k]


@kernel(inline="always")
def _merge_into(
    keys: np.ndarray, src: np.ndarray, dst: np.ndarray, lo: int, mid: int, hi: int
) -> None:
    """``dst[lo:hi]``: the ascending runs ``src[lo:mid]`` and ``src[mid:hi]`` merged, the left
    run winning ties (stable)."""
    a, b, k = lo, mid, lo
    while a < mid and b < hi:
        if keys[src[b]] < keys[src[a]]:
            dst[k] = src[b]
            b += 1
        else:
            dst[k] = src[a]
            a += 1
        k += 1
    while a < mid:
        dst[k] = src[a]
        a += 1
        k += 1
    while b < hi:
        dst[k] = src[b]
        b += 1
        k += 1


@kernel
def nonzero(mask: np.ndarray) -> np.ndarray:
    """Indices where ``mask`` is true (``np.flatnonzero`` of a 1-D array)."""
    count = 0
    for k in range(mask.size):
        count += mask[k]
    out = np.empty(count, dtype=np.int64)
    nonzero_into(mask, out)
    return out


@kernel
def nonzero_into(mask: np.ndarray, out: np.ndarray) -> int:
    """:func:`nonzero` written into ``out`` (at least as long as the count); the count."""
    m = 0
    for k in range(mask.size):
        if mask[k]:
            out[m] = k
            m += 1
    return m


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


@kernel(inline="always")
def _after(keys: np.ndarray, p: int, q: int) -> bool:
    """Whether index p comes after index q in the stable order of ``keys``: a larger key, or
    an equal key and a larger index."""
    return keys[p] > keys[q] or (keys[p] == keys[q] and p > q)


@kernel(inline="always")
def _insertion_sort(keys: np.ndarray, order: np.ndarray, n: int, budget: int) -> int:
    """``order[:n]`` sorted in place by key, then index (:func:`_after`), by insertion; the
    moves it took, or -1 (``order`` then half sorted) once they exceed ``budget``."""
    moves = 0
    for i in range(1, n):
        item = order[i]
        j = i - 1
        while j >= 0 and _after(keys, order[j], item):
            order[j + 1] = order[j]
            j -= 1
        order[j + 1] = item
        moves += i - 1 - j
        if moves > budget:
            return -1
    return moves


@kernel
def resort_into(
    keys: np.ndarray, order: np.ndarray, n_kept: int, added: np.ndarray, n_added: int,
    budget: int,
) -> bool:  # fmt: skip
    """The stable order of ``keys`` (as :func:`stable_argsort`) in ``order[:keys.size]``,
    from a nearly sorted start: ``order[:n_kept]`` holds some indices in about their order
    (the previous step's), ``added[:n_added]`` the others, and ``n_kept + n_added ==
    keys.size``.

    Both parts are put in order by insertion, which costs one comparison per index and one
    move per inversion, then merged from the back of ``order``. Equal keys are ordered by
    index, so the result is the one stable order whatever the start. False (``order`` then
    undefined) when they need more than ``budget`` moves or a key is NaN: the caller sorts
    afresh.
    """
    for p in range(keys.size):
        if keys[p] != keys[p]:
            return False
    moves = _insertion_sort(keys, order, n_kept, budget)
    if moves < 0 or _insertion_sort(keys, added, n_added, budget - moves) < 0:
        return False
    a, b = n_kept - 1, n_added - 1
    for w in range(n_kept + n_added - 1, -1, -1):  # the larger tail goes last
        if b < 0:
            break
        if a >= 0 and _after(keys, order[a], added[b]):
            order[w] = order[a]
            a -= 1
        else:
            order[w] = added[b]
            b -= 1
    return True
