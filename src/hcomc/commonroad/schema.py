"""CommonRoad's own check of a file: the XML schema (XSD) that commonroad-io ships.

:func:`schema_valid` is commonroad-io's verdict
(``CommonRoadFileWriter.check_validity_of_commonroad_file``); :func:`schema_errors` gives
the reasons, read against the same XSD file. (``CommonRoadFileWriter.write_to_file`` with
``check_validity=True`` runs the check but discards its result, so it never tells.)
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import commonroad
from commonroad.common.file_writer import CommonRoadFileWriter
from commonroad.common.util import FileFormat
from lxml import etree

__all__ = ["XSD_NAME", "schema_errors", "schema_path", "schema_valid"]

XSD_NAME = "XML_commonRoad_XSD.xsd"
"""The scenario schema's file name in commonroad-io."""


def schema_valid(path: Path) -> bool:
    """commonroad-io's verdict on the XML file ``path``."""
    return bool(
        CommonRoadFileWriter.check_validity_of_commonroad_file(path.read_bytes(), FileFormat.XML)
    )


@cache
def schema_path() -> Path:
    """The XSD file commonroad-io checks scenarios against."""
    found = sorted(Path(commonroad.__file__).parent.rglob(XSD_NAME))
    if not found:
        raise FileNotFoundError(f"commonroad-io ships no {XSD_NAME} here")
    return found[0]


def schema_errors(path: Path) -> list[str]:
    """Why ``path`` fails the schema: ``line N: message`` per error (empty if it passes)."""
    schema = etree.XMLSchema(etree.parse(str(schema_path())))
    if schema.validate(etree.parse(str(path))):
        return []
    return [f"line {e.line}: {e.message}" for e in schema.error_log]
