"""Which code computed a stored run: a fingerprint of the sources that can change results.

A resumed sweep or comparison keys its stored runs with :func:`code_stamp` (beside the
resolved config and the package version), so that a run computed by other code — a
checkout at another revision, an edited model — is recomputed, never mixed into a table
with runs of the current code. The subpackages that only read, print and draw results
(:data:`RESULT_FREE`) are left out, so editing them keeps stored runs valid.
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1]
"""The directory of the hcomc package."""

RESULT_FREE = ("cli", "viz")
"""Subpackages whose code does not change a run's results."""


@functools.cache
def code_stamp(package: Path = PACKAGE) -> str:
    """SHA-256 of the paths and contents of the package's ``.py`` files outside
    :data:`RESULT_FREE` (computed once per process)."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        relative = path.relative_to(package)
        if relative.parts[0] not in RESULT_FREE:
            digest.update(relative.as_posix().encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()
