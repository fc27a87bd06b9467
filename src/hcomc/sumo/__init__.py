"""Eclipse SUMO interoperability: scenario export, trajectory exchange and co-simulation.

Everything here needs the optional extra ``pip install "hcomc[sumo]"`` (the ``eclipse-sumo``
wheel ships the ``sumo`` and ``netconvert`` binaries, ``libsumo`` runs SUMO in process,
``sumolib`` reads its XML). Only the top layer (CLI, experiment runner) imports this package.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
from pathlib import Path
from typing import Any

__all__ = ["INSTALL_HINT", "SumoFormatError", "SumoMissingError", "sumo_binary"]

INSTALL_HINT = 'pip install "hcomc[sumo]"'


class SumoMissingError(RuntimeError):
    """SUMO (binaries or Python bindings) is not installed."""


class SumoFormatError(ValueError):
    """A SUMO network, FCD or trajectory file does not fit: names file, element, expectation."""


def sumo_home() -> Path | None:
    """SUMO_HOME of the ``eclipse-sumo`` wheel, else the environment's, else None."""
    try:
        import sumo  # the eclipse-sumo wheel

        return Path(sumo.SUMO_HOME)
    except ImportError:
        home = os.environ.get("SUMO_HOME")
        return Path(home) if home else None


def sumo_binary(name: str) -> str:
    """Path of a SUMO executable (``sumo``, ``netconvert``) from the wheel or PATH."""
    home = sumo_home()
    if home is not None:
        candidate = home / "bin" / name
        if candidate.is_file():
            return str(candidate)
    found = shutil.which(name)
    if found is None:
        raise SumoMissingError(f"SUMO's '{name}' executable was not found; {INSTALL_HINT}")
    return found


def import_libsumo() -> Any:
    """The in-process SUMO API (``libsumo``), or :class:`SumoMissingError`."""
    # libsumo prints a pyarrow version notice with print(); keep stdout clean for --json
    notice = io.StringIO()
    try:
        with contextlib.redirect_stdout(notice):
            import libsumo
    except ImportError as exc:
        # the wheel also needs the system's libGL / libX11 (e.g. Debian's libgl1)
        raise SumoMissingError(
            f"the SUMO Python binding 'libsumo' cannot be imported ({exc}); {INSTALL_HINT}"
        ) from None
    return libsumo
