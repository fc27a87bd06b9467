"""The base of hcomc's parameter models: a frozen pydantic v2 model that rejects unknown keys.

Frozen, so a validated config cannot change under a run that holds it; ``extra="forbid"``, so
a misspelt key is an error rather than a silently ignored setting.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict

__all__ = ["FrozenModel"]


class FrozenModel(BaseModel):
    """A pydantic model that cannot be changed once validated and rejects unknown keys."""

    model_config = ConfigDict(frozen=True, extra="forbid")
