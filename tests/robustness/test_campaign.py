"""``hcomc faults``: the campaign end to end through the CLI, resumable and never mixed,
and docs/robustness.md against the data it was generated from."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config.impairment_tables import CHANNELS, FAULTS
from hcomc.robustness.campaign import CampaignSpec, FaultRun, run_campaign, run_faulted
from hcomc.robustness.publish import data_dir, generated_part, markers, published_runs
from hcomc.robustness.tables import CELL, summarise

runner = CliRunner()
DOCS = Path(__file__).resolve().parents[2] / "docs"

SMALL = ["faults", "--seeds", "2", "--conditions", "C2", "--configurations", "FIFO,HCOMC",
         "--faults", "none,brake-vmf", "--channels", "ideal,lat300-loss30-bursty",
         "--workers", "1"]  # fmt: skip


def test_campaign_runs_resumes_and_refuses_to_mix(tmp_path, monkeypatch):
    out = tmp_path / "faults"
    first = runner.invoke(app, [*SMALL, "--out", str(out)])
    assert first.exit_code == 0, first.output
    assert "cells: 16/16 (100 %)" in first.stderr  # progress, off a terminal as lines
    runs = pd.read_csv(out / "runs.csv")
    assert (
        len(runs) == 1 * 2 * 2 * 2 * 2 * 2
    )  # conditions x configs x faults x channels x shield x seeds
    assert set(runs["fault"]) == {"none", "brake-vmf"}
    # one row per cell, equal to a pandas aggregation written out here
    summary = pd.read_csv(out / "summary.csv")
    assert len(summary) == 16
    for _, cell in summary.iterrows():
        mine = runs[(runs[CELL] == cell[CELL]).all(axis=1)]
        assert cell["runs"] == len(mine) == 2
        assert cell["collisions_commanded"] == mine["collisions_commanded"].sum()
        assert cell["merged"] == mine["merged"].sum()
    # every run is its pure function: one row recomputed alone equals the table's
    row = runs[(runs["configuration"] == "HCOMC") & (runs["fault"] == "brake-vmf")
               & (runs["channel"] == "lat300-loss30-bursty") & runs["shield"]].iloc[1]  # fmt: skip
    again = run_faulted(FaultRun("C2", "HCOMC", "brake-vmf", "lat300-loss30-bursty", True,
                                 int(row["seed"]), FAULTS["brake-vmf"],
                                 CHANNELS["lat300-loss30-bursty"]))  # fmt: skip
    for key in ("collisions", "plans", "plans_lost", "shield_brakes", "min_ttc", "merged"):
        assert again[key] == row[key] or (again[key] != again[key] and row[key] != row[key])
    # rerun: every cell is found done, nothing is recomputed
    parts = {p: p.stat().st_mtime_ns for p in (out / "parts").iterdir()}
    second = runner.invoke(app, [*SMALL, "--out", str(out)])
    assert second.exit_code == 0, second.output
    assert {p: p.stat().st_mtime_ns for p in (out / "parts").iterdir()} == parts
    # another spec in the same directory is refused, one line, exit 2
    other = runner.invoke(app, [*SMALL[:2], "3", *SMALL[3:], "--out", str(out)])
    assert other.exit_code == 2
    assert "another spec" in other.stderr
    assert other.stderr.strip().count("\n") == 0
    # so is the same spec with other code; the campaign's stamp keeps its first revision
    stamp = (out / "campaign.json").read_text()
    monkeypatch.setattr("hcomc.experiments.provenance.code_stamp", lambda: "edited")
    edited = runner.invoke(app, [*SMALL, "--out", str(out)])
    assert edited.exit_code == 2
    assert "code" in edited.stderr
    assert (out / "campaign.json").read_text() == stamp


def test_bad_campaign_options_are_one_line_errors(tmp_path):
    for args, fragment in (
        (["--faults", "fire"], "--faults"),
        (["--channels", "carrier-pigeon"], "--channels"),
        (["--conditions", "C9"], "--conditions"),
        (["--seeds", "0"], "--seeds"),
        (["--configurations", "Nobody"], "--configurations"),
    ):
        result = runner.invoke(app, ["faults", *args, "--out", str(tmp_path / "x")])
        assert result.exit_code == 2, (args, result.output)
        assert fragment in result.stderr
        assert result.stderr.strip().count("\n") == 0


@pytest.mark.parametrize("section", ["hcomc", "sumo", "hcomc-1000-seeds"])
def test_docs_page_is_generated_from_its_data(section):
    data = data_dir(DOCS, section)  # each published campaign's data
    runs = published_runs(data)
    meta = json.loads((data / "campaign.json").read_text())
    text = (DOCS / "robustness.md").read_text()
    begin, end = markers(section)
    part = text[text.index(begin) : text.index(end) + len(end)]
    assert part == generated_part(runs, meta)
    summary = pd.read_csv(data / "summary.csv")
    pd.testing.assert_frame_equal(summary, summarise(runs), check_dtype=False)
    spec = meta["spec"]
    assert set(runs["fault"]) == set(spec["faults"]) | {"none"}  # the nominal cells too
    assert set(runs["channel"]) == set(spec["channels"])
    assert len(runs) == len(runs.drop_duplicates([*CELL, "seed"]))
    assert CampaignSpec(**{k: tuple(v) if isinstance(v, list) else v
                           for k, v in spec.items()}).section == section  # fmt: skip
    if section == "hcomc":  # the whole catalogue, every channel
        assert set(spec["faults"]) == set(FAULTS)
        assert set(spec["channels"]) == set(CHANNELS)
    elif section == "sumo":
        assert spec["engine"] == "sumo"
        assert len(spec["seeds"]) >= 100
    else:  # brake-vmf at 1000 seeds: every condition, controller, channel, shield setting
        assert spec["faults"] == ["brake-vmf"]
        assert set(spec["channels"]) == set(CHANNELS)
        assert spec["conditions"] == ["C1", "C2", "C3", "C4", "C5"]
        assert spec["configurations"] == ["FIFO", "Game", "HCOMC"]
        assert len(spec["seeds"]) == 1000
        assert len(runs) == (5 * 3 * 3 * 2 + 5 * 3) * 1000


def test_the_sumo_campaign_is_told_as_the_data_has_it():
    """The hand-written account below the generated SUMO tables: its collisions and the
    merges with and without the shield, as its data has them."""
    runs = published_runs(data_dir(DOCS, "sumo"))
    text = " ".join((DOCS / "robustness.md").read_text().split())
    assert f"None of the {len(runs)} runs has a collision." in text
    assert runs["collisions"].sum() == 0
    merged = runs.groupby([*CELL])["merged"].sum().reset_index()
    on, off = merged[merged.shield.astype(bool)], merged[~merged.shield.astype(bool)]
    assert set(runs.groupby([*CELL]).size()) == {100}
    told = (f"with it on, {on.merged.min()} to {on.merged.max()} of a cell's 100 ramp vehicles "
            f"merge, without it {off.merged.min()} to {off.merged.max()}")  # fmt: skip
    assert told in text
    assert "(in our engine every one does, first table)" in text
    assert published_runs(data_dir(DOCS, "hcomc"))["merged"].astype(bool).all()


@pytest.mark.slow
def test_local_processes_and_a_dask_cluster_give_the_same_runs(tmp_path):
    distributed = pytest.importorskip("distributed")
    spec = CampaignSpec(conditions=("C4",), configurations=("HCOMC",), faults=("brake-vmf",),
                        channels=("lat100-loss10",), seeds=(0, 1))  # fmt: skip
    local = run_campaign(spec, tmp_path / "local", workers=2)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:  # fmt: skip
        remote = run_campaign(spec, tmp_path / "dask", scheduler=cluster.scheduler_address)
    columns = [c for c in local.columns if c != "wall_s"]
    pd.testing.assert_frame_equal(local[columns], remote[columns])
    assert len(local) == 3 * 2  # shield off/on and the nominal cell they are paired with
    nominal = local[(local.fault == "none") & (local.channel == "ideal") & ~local.shield]
    assert nominal.seed.tolist() == [0, 1]
