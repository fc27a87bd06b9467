"""docs/robustness.md and its data, from a finished campaign directory.

The page keeps its written text (what the campaign does, how to rerun it) and replaces the
part between :data:`BEGIN` and :data:`END` with :func:`hcomc.robustness.tables.page` of the
campaign's runs; the runs and the per-cell summary go to ``DOCS/data/robustness/``, so a test
can check the page against the data it came from.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pandas as pd

from hcomc.config import ConfigError
from hcomc.robustness.tables import page
from hcomc.sim.manifest import atomic_paths

__all__ = ["BEGIN", "END", "generated_part", "publish"]

BEGIN = "<!-- robustness tables: begin -->"
END = "<!-- robustness tables: end -->"


def _stamp(campaign: Path) -> str:
    meta = json.loads((campaign / "campaign.json").read_text())
    return f"hcomc {meta['version']}, revision {meta['revision']}"


def generated_part(runs: pd.DataFrame, stamp: str, seeds: int) -> str:
    """The page's generated part for ``runs``."""
    command = f"hcomc faults --seeds {seeds} --out results/faults --docs docs"
    return f"{BEGIN}\n{page(runs, stamp, command)}\n{END}"


def publish(campaign: Path, docs: Path, *, seeds: int) -> Path:
    """Write ``docs/robustness.md``'s tables and ``docs/data/robustness/{runs,summary}.csv``
    from ``campaign``; returns the page's path."""
    target = docs / "robustness.md"
    if not target.exists():
        raise ConfigError(f"option '--docs' = '{docs}': no robustness.md there to update")
    text = target.read_text()
    if BEGIN not in text or END not in text:
        raise ConfigError(f"{target} has no '{BEGIN}' ... '{END}' section to replace")
    runs = pd.read_csv(campaign / "runs.csv")
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    data = docs / "data" / "robustness"
    data.mkdir(parents=True, exist_ok=True)
    for name in ("runs.csv", "summary.csv"):
        shutil.copyfile(campaign / name, data / name)
    shutil.copyfile(campaign / "campaign.json", data / "campaign.json")
    with atomic_paths(target) as (tmp,):
        tmp.write_text(head + generated_part(runs, _stamp(campaign), seeds) + tail)
    return target
