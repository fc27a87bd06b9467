"""The C library's ``exp`` and ``log`` and IEEE 754 division on Python floats, with the special
values of IEEE 754 where Python raises.

The compiled optimisers take every transcendental function from the C library (through numba
in the kernels, through Python's ``math`` here) and never from numpy: numpy picks its float64
``exp``, ``log`` and ``power`` by the CPU at run time (its SIMD versions for AVX-512 differ from
the C library's in the last bit on many arguments), so a run computed with them would depend on
the processor. Python's ``math`` raises where the C functions return a special value (``log``
of 0, an ``exp`` that overflows), and ``/`` raises on a zero divisor; these functions return
what the C library and the kernels (numba with numpy's error model) return there instead.
"""

from __future__ import annotations

import math

__all__ = ["divide", "exp", "log", "sin"]


def exp(x: float) -> float:
    """``e ** x`` by the C library's ``exp``; inf where it overflows."""
    try:
        return math.exp(x)
    except OverflowError:
        return math.inf


def log(x: float) -> float:
    """The natural logarithm by the C library's ``log``: -inf at 0 (either sign), NaN below."""
    if x == 0.0:
        return -math.inf
    if x < 0.0:
        return math.nan
    return math.log(x)


def sin(x: float) -> float:
    """The C library's ``sin``; NaN at +-inf."""
    return math.sin(x) if not math.isinf(x) else math.nan


def divide(a: float, b: float) -> float:
    """``a / b`` in IEEE 754 arithmetic: a signed infinity for a non-zero ``a`` over a zero
    ``b`` (the product of their signs), NaN for 0 or NaN over 0."""
    if b != 0.0:  # NaN included
        return a / b
    if a == 0.0 or math.isnan(a):
        return math.nan
    return math.copysign(math.inf, a) * math.copysign(1.0, b)
