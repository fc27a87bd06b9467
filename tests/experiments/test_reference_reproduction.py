"""The default reproduction gives the published numbers on this machine, whatever its processor.

``hcomc reproduce`` with its defaults (30 seeds, every condition and configuration) runs here,
and its digest (``hcomc docs`` writes it to ``docs/data``) must equal the committed one, every
column but the decision times (wall-clock): the claims with their verdicts, Tables II/III and
the paper scenario, float for float. A host on which any number of the reproduction differs
fails here; ``tests/scenario/test_fingerprints.py`` says which runs moved.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.experiments.digest import digest, save

DATA = Path(__file__).resolve().parents[2] / "docs" / "data"
TIMINGS = ("decision_ms",)
"""Columns that are wall-clock times, not results."""


def test_the_default_reproduction_equals_the_published_digest(tmp_path: Path) -> None:
    out = tmp_path / "results"
    done = CliRunner().invoke(app, ["reproduce", "--out", str(out)])
    assert done.exit_code == 0, done.output
    written = save(digest(out), tmp_path / "data")
    for path in written[1:]:  # run.json: command, version and revision, not results
        fresh = pd.read_csv(path, keep_default_na=False)
        published = pd.read_csv(DATA / path.name, keep_default_na=False)
        drop = [c for c in TIMINGS if c in published.columns]
        pd.testing.assert_frame_equal(
            fresh.drop(columns=drop), published.drop(columns=drop), check_exact=True, obj=path.name
        )
