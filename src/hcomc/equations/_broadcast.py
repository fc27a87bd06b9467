"""Apply a compiled scalar kernel elementwise with numpy broadcasting.

Each equation of :mod:`hcomc.equations` is implemented once, as a scalar numba kernel; its
array form broadcasts the arguments to float64 arrays, runs a compiled loop over them and
restores the shape.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from hcomc._typing import FloatArray


def broadcast_apply(loop: Callable[..., Any], *args: Any) -> FloatArray:
    """``loop(*flat_args)`` on the float64 broadcast of ``args``, reshaped to their shape.

    ``loop`` is a compiled function taking 1-D float64 arrays of equal length and returning
    one result array of that length (the elementwise application of a scalar kernel), or of
    shape (length, k) for a kernel with k results (the shape is then ``(*shape, k)``).
    """
    arrays = [np.asarray(a, dtype=np.float64) for a in args]
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    # one compiled signature: contiguous, writeable float64 (a copy only where needed)
    flat = [
        np.require(a if a.shape == shape else np.broadcast_to(a, shape), None, ["C", "W"]).reshape(
            -1
        )
        for a in arrays
    ]
    out = np.asarray(loop(*flat), dtype=np.float64)
    return out.reshape(shape + out.shape[1:])
