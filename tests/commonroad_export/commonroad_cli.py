"""The CLI as the CommonRoad tests call it."""

from __future__ import annotations

from typer.testing import CliRunner

from hcomc.cli import app


def invoke(*args: str) -> tuple[int, str]:
    """``hcomc ARGS``: exit code and output (stdout and stderr)."""
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, result.output
