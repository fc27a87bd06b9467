"""Consecutive same-lane pairs of key vehicles, row by row, from their logged cells
(compiled): the gaps and closing speeds the surrogate safety metrics read
(:func:`hcomc.metrics.window.key_pairs` takes them from a log).
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel

__all__ = ["consecutive_pairs"]


@kernel(inline="always")
def _comes_before(lane_a: int, x_a: float, lane_b: int, x_b: float) -> bool:
    """Order of (lane, x) sort keys: by lane, then by x with NaN after numbers (numpy's)."""
    if lane_a != lane_b:
        return lane_a < lane_b
    return x_a < x_b or (math.isnan(x_b) and not math.isnan(x_a))


@kernel
def consecutive_pairs(
    act: np.ndarray, x: np.ndarray, v: np.ndarray, lane: np.ndarray, length: np.ndarray,
    gap: np.ndarray, closing: np.ndarray, valid: np.ndarray,
) -> None:  # fmt: skip
    """:func:`hcomc.metrics.window.key_pairs` of the (R, K) cells of the key vehicles into
    (R, K - 1) ``gap``, ``closing`` and ``valid``: per row a stable sort by (lane, x),
    inactive vehicles last (as :func:`numpy.lexsort` of those keys orders them), then each
    neighbour pair."""
    n_keys = x.shape[1]
    order = np.empty(n_keys, dtype=np.int64)
    lane_key, x_key = np.empty(n_keys, dtype=np.int64), np.empty(n_keys)
    for k in range(x.shape[0]):
        for c in range(n_keys):
            lane_key[c] = lane[k, c] if act[k, c] else np.iinfo(np.int64).max
            x_key[c] = x[k, c] if act[k, c] else np.inf
        for i in range(n_keys):  # stable insertion sort of the K (six) key vehicles
            j = i - 1
            while j >= 0 and _comes_before(lane_key[i], x_key[i], lane_key[order[j]],
                                           x_key[order[j]]):  # fmt: skip
                order[j + 1] = order[j]
                j -= 1
            order[j + 1] = i
        for p in range(n_keys - 1):
            f, ld = order[p], order[p + 1]  # follower, leader
            valid[k, p] = act[k, f] and act[k, ld] and lane[k, f] == lane[k, ld]
            # in float64, as numpy computes them from the float64 cells
            x_f, x_l = np.float64(x[k, f]), np.float64(x[k, ld])
            gap[k, p] = x_l - np.float64(length[ld]) - x_f
            closing[k, p] = np.float64(v[k, f]) - np.float64(v[k, ld])
