"""Shared pieces of the corridor models: the frozen base model and the error they raise.

A rule that involves several keys (a ramp past the road's end, overlapping lanes) cannot be a
field constraint; its validator raises :class:`RuleError`, which carries the key path
relative to the model being validated, so :mod:`hcomc.corridor.loading` can name the full
path (``road.on_ramps[2].x``), the value and what is allowed.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict

__all__ = ["ID_PATTERN", "NO_VALUE", "RESERVED_IDS", "Frozen", "RuleError"]

ID_PATTERN = r"^[A-Za-z][A-Za-z0-9-]*$"
"""Ramp ids: a letter, then letters, digits and hyphens (they become SUMO edge ids and parts
of flow ids, whose separator is ``_``)."""

RESERVED_IDS = frozenset({"main", "exit"})
"""``main`` is the mainline origin, ``exit`` the mainline's downstream end (a destination)."""


class Frozen(BaseModel):
    """Immutable model that rejects unknown keys (a typo is an error, never ignored)."""

    model_config = ConfigDict(frozen=True, extra="forbid")


class RuleError(ValueError):
    """A value breaks a rule that involves other keys.

    ``key`` is the path relative to the model whose validator raised it (``on_ramps[2].x``),
    ``value`` the offending value (:data:`NO_VALUE` when the key itself is wrong),
    ``problem`` what is wrong (optional) and ``allowed`` what would be accepted.
    """

    def __init__(self, key: str, value: Any, allowed: str, problem: str = "") -> None:
        self.key, self.value, self.allowed, self.problem = key, value, allowed, problem
        super().__init__(self.message())

    def message(self, prefix: str = "") -> str:
        """``key '<prefix>.<key>' = <value>: <problem>; allowed: <allowed>``."""
        key = f"{prefix}.{self.key}" if prefix else self.key
        shown = "" if self.value is NO_VALUE else f" = {self.value!r}"
        problem = f"{self.problem}; " if self.problem else ""
        return f"key '{key}'{shown}: {problem}allowed: {self.allowed}"


NO_VALUE: Any = object()
"""``value`` of a :class:`RuleError` whose key itself is the problem (an unknown name)."""
