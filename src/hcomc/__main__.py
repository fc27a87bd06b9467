"""``python -m hcomc`` runs the command-line interface."""

from hcomc.cli import app

app(prog_name="hcomc")
