"""Command-line interface (typer + rich).

Every command validates its input before anything runs; a bad value prints one line naming
the key, the value and what is allowed, and exits with status 2 (no traceback).
"""

# Importing the command modules registers their commands on ``app``, in help order.
# isort: off
from hcomc.cli import simulate  # noqa: F401
from hcomc.cli import plan  # noqa: F401
from hcomc.cli import experiments  # noqa: F401
from hcomc.cli import reproduce  # noqa: F401
from hcomc.cli import compare  # noqa: F401
from hcomc.cli import figures  # noqa: F401
from hcomc.cli import replay  # noqa: F401
from hcomc.cli import faults  # noqa: F401
from hcomc.cli import falsify  # noqa: F401

# isort: on
from hcomc.cli._app import app

__all__ = ["app"]


def _register_sumo() -> None:
    """SUMO interoperability commands (need the optional extra only when they run)."""
    from hcomc.cli import trajectories  # noqa: F401  (registers `export trajectories`)
    from hcomc.cli.sumo import export_app, metrics

    app.add_typer(export_app, name="export")
    app.command("metrics")(metrics)


_register_sumo()
