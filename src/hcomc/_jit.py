"""How hcomc compiles its kernels: one decorator, one policy.

Every compiled function of hcomc is declared with :data:`kernel`, numba's ``njit`` with

* ``cache=True``: compiled once per machine and loaded from ``__pycache__`` afterwards;
* ``error_model="numpy"``: a floating-point division by zero gives inf or NaN, as it does in
  numpy, instead of raising ``ZeroDivisionError``. Every other result is the same under both
  models; numpy's spares the test for zero before each division, which makes the merge
  prediction's kernels about a sixth faster.

Use it bare (``@kernel``) or with numba's other options (``@kernel(inline="always")``,
``@kernel(parallel=True)``).
"""

from __future__ import annotations

from functools import partial
from typing import Any

from numba import njit

kernel: Any = partial(njit, cache=True, error_model="numpy")
"""numba's ``njit`` with hcomc's compilation policy (module docstring)."""

__all__ = ["kernel"]
