"""What a figure's input names: a data file or directory to read, or a scenario to simulate.

Shared by the figure kinds of :mod:`hcomc.viz.inputs` and the corridor kinds of
:mod:`hcomc.viz.corridor_inputs`, which both tell the two apart before they load anything.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["Source", "is_scenario"]

Source = str | os.PathLike[str]
"""A figure input: a path, or the name of a preset."""


def is_scenario(source: Source) -> bool:
    """A preset name (scenario or corridor) or a TOML file: something to simulate, as
    opposed to a data file or directory to read."""
    path = Path(source)
    if path.suffix.lower() == ".toml":
        return True
    if path.exists():
        return False
    from hcomc.config import preset_names
    from hcomc.corridor import corridor_preset_names

    names = [*preset_names(), *corridor_preset_names()]
    return str(source).lower() in {name.lower() for name in names}
