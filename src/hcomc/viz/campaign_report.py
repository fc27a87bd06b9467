"""A campaign's HTML report: the overview table, what its paired effects say, and its worst
runs, each linked to a config that ``hcomc simulate`` runs again and to its replay.

A cell's settings are config tables (``faults``, ``[v2x]``, ``[shield]``,
:mod:`hcomc.config.impairment_tables`), so a run of the campaign is the run of the config
:func:`run_config` writes, bit for bit: the report re-simulates its worst runs that way. The
worst runs are those with a collision involving a commanded vehicle, else the run with the
least TTC of each configuration; runs on corridors are listed without a replay (a corridor
replay needs trajectories the campaign does not record).
"""

from __future__ import annotations

import html
from pathlib import Path

import pandas as pd

from hcomc.config import ScenarioConfig, config_to_toml, load_config
from hcomc.config.impairment_tables import CHANNELS, FAULTS
from hcomc.robustness.campaign import FaultRun
from hcomc.robustness.tables import OVERVIEW, overview_view, summarise, verdicts
from hcomc.sim.manifest import atomic_paths

__all__ = ["run_config", "worst_runs", "write_report"]

MAX_SHOWN = 20
"""Most worst runs a report re-simulates."""


def run_config(condition: str, configuration: str, fault: str, channel: str, shield: bool,
               seed: int) -> ScenarioConfig:  # fmt: skip
    """The config of one campaign run (a paper condition), its seed inside: the cell's
    settings as the config's tables (:meth:`hcomc.robustness.campaign.FaultRun.tables`)."""
    from hcomc.experiments.runner import configuration_overrides

    run = FaultRun(condition, configuration, fault, channel, shield, seed, FAULTS[fault],
                   CHANNELS[channel])  # fmt: skip
    overrides = configuration_overrides(configuration, {})
    return load_config(condition, **overrides, **run.tables(), seed=int(seed))


def worst_runs(runs: pd.DataFrame) -> pd.DataFrame:
    """Runs with a commanded collision (at most :data:`MAX_SHOWN`), else per configuration
    its run of least TTC."""
    hit = runs[runs["collisions_commanded"] > 0]
    if len(hit):
        return hit.sort_values(["configuration", "fault", "channel", "seed"]).head(MAX_SHOWN)
    least = runs.loc[runs.groupby("configuration", sort=False)["min_ttc"].idxmin()]
    return least.head(MAX_SHOWN)


def write_report(out: Path, runs: pd.DataFrame, corridors: tuple[str, ...] = ()) -> Path:
    """``out/report.html`` and, per worst run of a paper condition, ``out/worst/<name>.toml``
    and ``.html``; returns the report's path."""
    from hcomc.robustness.impairments import listeners_of
    from hcomc.sim.engine import Simulation
    from hcomc.viz.replay import write_replay

    folder = out / "worst"
    folder.mkdir(parents=True, exist_ok=True)
    items = []
    for row in worst_runs(runs).to_dict("records"):
        shield = bool(row["shield"])
        name = (f"{row['condition']}-{row['configuration']}-{row['fault']}-{row['channel']}-"
                f"shield-{'on' if shield else 'off'}-seed-{row['seed']}")  # fmt: skip
        name = "".join(c if c.isalnum() or c in "-_." else "_" for c in name)
        what = (f"{row['condition']} · {row['configuration']} · {row['fault']} · {row['channel']} "
                f"· shield {'on' if shield else 'off'} · seed {row['seed']}: collisions with a "
                f"commanded vehicle {row['collisions_commanded']}, least TTC "
                f"{row['min_ttc']:.2f} s")  # fmt: skip
        if row["condition"] in corridors:
            items.append(f"<li>{html.escape(what)} (a corridor run: no replay)</li>")
            continue
        config = run_config(row["condition"], row["configuration"], row["fault"],
                            row["channel"], shield, row["seed"])  # fmt: skip
        (folder / f"{name}.toml").write_text(config_to_toml(config), encoding="utf-8")
        log = Simulation(config, listeners=listeners_of(config)).run()
        write_replay(folder / f"{name}.html", [log], titles=[what])
        items.append(f'<li>{html.escape(what)}: <a href="worst/{name}.html">replay</a>, '
                     f'<a href="worst/{name}.toml">config</a> '
                     f"(<code>hcomc simulate worst/{name}.toml</code>)</li>")  # fmt: skip
    overview = summarise(runs, OVERVIEW)
    page = "\n".join([
        "<!doctype html>", '<html lang="en"><head><meta charset="utf-8">',
        "<title>hcomc faults: robustness campaign</title>",
        "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:2px 6px;font-size:13px}</style></head><body>",
        f"<h1>Robustness campaign: {len(runs)} runs</h1>",
        overview_view(overview).to_html(index=False, border=0),
        f"<p>{html.escape(verdicts(overview))}</p>",
        "<h2>Worst runs</h2>", f"<ul>{''.join(items)}</ul>", "</body></html>",
    ])  # fmt: skip
    target = out / "report.html"
    with atomic_paths(target) as (tmp,):
        tmp.write_text(page, encoding="utf-8")
    return target
