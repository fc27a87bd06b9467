"""docs/robustness.md and its data, from a finished campaign directory.

The page keeps its written text (what the campaign does, how to rerun it) and replaces the
part between the campaign engine's :func:`markers` with :func:`hcomc.robustness.tables.page`
of the campaign's runs, headed by the command that made them; the runs, the per-cell summary
and the campaign's stamp go to :func:`data_dir`, so a test can check the page against the
data it came from. ``hcomc faults --docs`` publishes a campaign it finished;
``python -m hcomc.robustness.publish DIR --docs docs`` publishes a finished campaign
directory again (or renders the tables anew from the published data, ``DIR`` being
:func:`data_dir`), without running anything.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path
from typing import Any

import pandas as pd

from hcomc.config import ConfigError
from hcomc.robustness.campaign import CampaignSpec
from hcomc.robustness.tables import page, summarise
from hcomc.sim.manifest import atomic_paths

__all__ = ["data_dir", "generated_part", "markers", "publish", "published_runs"]


def markers(section: str) -> tuple[str, str]:
    """The comments around the generated part of a campaign's ``section``
    (:attr:`~hcomc.robustness.campaign.CampaignSpec.section`: ``hcomc``, ``sumo``,
    ``hcomc-1000-seeds`` ...)."""
    where = {"hcomc": "", "sumo": " in SUMO"}.get(section, f" ({section})")
    return f"<!-- robustness tables{where}: begin -->", f"<!-- robustness tables{where}: end -->"


def data_dir(docs: Path, section: str) -> Path:
    """Where a campaign's runs, summary and stamp are kept under ``docs``."""
    base = docs / "data" / "robustness"
    return base if section == "hcomc" else base / section


LARGE_RUNS = 20_000
"""Runs from which the published runs table is kept gzip-compressed (``runs.csv.gz``)."""


def published_runs(folder: Path) -> pd.DataFrame:
    """The runs table of a campaign directory or its published data: ``runs.csv``, or
    ``runs.csv.gz`` for a large campaign."""
    plain = folder / "runs.csv"
    return pd.read_csv(plain if plain.exists() else folder / "runs.csv.gz")


def _keep_runs(runs: pd.DataFrame, data: Path) -> None:
    """Write ``runs`` under ``data`` (compressed when large), removing the other form."""
    name = "runs.csv.gz" if len(runs) > LARGE_RUNS else "runs.csv"
    with atomic_paths(data / name) as (tmp,):
        gzip = {"method": "gzip", "mtime": 0}  # the same bytes for the same runs
        runs.to_csv(tmp, index=False, compression=gzip if name.endswith(".gz") else None)
    other = data / ("runs.csv" if name.endswith(".gz") else "runs.csv.gz")
    other.unlink(missing_ok=True)


def _spec(meta: dict[str, Any]) -> CampaignSpec:
    fields: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v
                              for k, v in meta["spec"].items()}  # fmt: skip
    return CampaignSpec(**fields)


def _stamp(meta: dict[str, Any]) -> str:
    sumo = f", SUMO {meta['sumo_version']}" if "sumo_version" in meta else ""
    return f"hcomc {meta['version']}, revision {meta['revision']}{sumo}"


def generated_part(runs: pd.DataFrame, meta: dict[str, Any]) -> str:
    """The page's generated part for ``runs`` of the campaign stamped ``meta``."""
    spec = _spec(meta)
    begin, end = markers(spec.section)
    return f"{begin}\n{page(runs, _stamp(meta), spec.command())}\n{end}"


def publish(campaign: Path, docs: Path) -> Path:
    """Write ``docs/robustness.md``'s tables of ``campaign`` and its runs, summary and stamp
    (under :func:`data_dir`); returns the page's path."""
    target = docs / "robustness.md"
    if not target.exists():
        raise ConfigError(f"option '--docs' = '{docs}': no robustness.md there to update")
    meta = json.loads((campaign / "campaign.json").read_text())
    section = _spec(meta).section
    begin, end = markers(section)
    text = target.read_text()
    if begin not in text or end not in text:
        raise ConfigError(f"{target} has no '{begin}' ... '{end}' section to replace")
    runs = published_runs(campaign)
    head, rest = text.split(begin, 1)
    tail = rest.split(end, 1)[1]
    data = data_dir(docs, section)
    data.mkdir(parents=True, exist_ok=True)
    if (campaign / "campaign.json").resolve() != (data / "campaign.json").resolve():
        shutil.copyfile(campaign / "campaign.json", data / "campaign.json")
    _keep_runs(runs, data)
    with atomic_paths(data / "summary.csv") as (tmp,):
        summarise(runs).to_csv(tmp, index=False)
    with atomic_paths(target) as (tmp,):
        tmp.write_text(head + generated_part(runs, meta) + tail)
    return target


def main(argv: list[str] | None = None) -> None:
    """``python -m hcomc.robustness.publish CAMPAIGN [--docs DOCS]``."""
    parser = argparse.ArgumentParser(description=publish.__doc__)
    parser.add_argument("campaign", type=Path, help="a finished campaign directory")
    parser.add_argument("--docs", type=Path, default=Path("docs"), help="the docs directory")
    args = parser.parse_args(argv)
    try:
        print(f"wrote {publish(args.campaign, args.docs)}")
    except (ConfigError, FileNotFoundError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None


if __name__ == "__main__":
    main()
