"""A reproduction run in brief: the small data files the published documentation is made from.

:func:`digest` reads a results directory of ``hcomc reproduce`` (the runs table, the paper
scenario's runs, the run record ``reproduce.json`` and the per-run manifests) and condenses it
into a :class:`Digest`: the run's provenance, every claim with its verdicts
(:func:`hcomc.experiments.claims.claims`), Tables II and III as numbers
(:func:`hcomc.experiments.tables.table_summary`), what the controllers decided per condition
and configuration, and the paper scenario's runs. :func:`save` writes it as
:data:`DATA_FILES` (a few kB of CSV and JSON, committed next to the documentation) and
:func:`load` reads them back exactly, so the documentation can be checked against the files
it was made from.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hcomc.experiments.claims import claims
from hcomc.experiments.paper import PAPER_METRICS
from hcomc.experiments.tables import table_summary
from hcomc.sim.manifest import atomic_paths

RUN_RECORD = "reproduce.json"
"""The record ``hcomc reproduce`` writes beside its results: its command line and settings."""

DATA_FILES = ("run.json", "claims.csv", "tables.csv", "decisions.csv", "paper_scenario.csv")
"""The files of a saved digest, in a data directory."""

SETTINGS = {
    "a_merg": ("control", "safety_emergency_decel"),
    "safety_threshold": ("control", "safety_threshold"),
    "virtual_max_decel": ("control", "virtual_max_decel"),
    "cav_time_headway": ("cav", "time_headway"),
    "duration": ("duration",),
    "road_length": ("road", "length"),
}
"""Config values the documentation quotes: name -> path in a run's resolved config."""

SCENARIO_COLUMNS = ("condition", "configuration", "mode", "sequence", *PAPER_METRICS)
"""Columns of the paper scenario's runs kept in the digest (plus ``collisions`` and
``merged`` when the runs have them)."""

_NA = "nan"  # how a missing value is written, so that an empty string stays a string


@dataclass(frozen=True)
class Provenance:
    """Where a run came from: its command, code version and scope.

    ``settings`` holds the config values of :data:`SETTINGS` and ``cav_penetration`` per
    condition, read from the run's manifests (so ``--set`` changes are reflected).
    """

    command: str
    version: str
    revision: str
    seeds: int
    seeded_runs: int
    scenario_runs: int
    conditions: tuple[str, ...]
    configurations: tuple[str, ...]
    settings: dict[str, Any]


@dataclass(frozen=True)
class Digest:
    """A reproduction run in brief (see the module docstring)."""

    provenance: Provenance
    claims: pd.DataFrame
    tables: pd.DataFrame
    decisions: pd.DataFrame
    scenario: pd.DataFrame


TEXT_COLUMNS = ("mode", "sequence", "eq19_branch", "vmc_kind", "vr_kind", "lateral_cause")
"""Text columns of a runs table, where "" means "none" (a CSV reads them back as NaN)."""


def _read_table(results: Path, stem: str) -> pd.DataFrame:
    """``<stem>.parquet``, else ``<stem>.csv`` (its empty texts restored) of a results dir."""
    parquet, csv = results / f"{stem}.parquet", results / f"{stem}.csv"
    if parquet.is_file():
        return pd.read_parquet(parquet)
    if csv.is_file():
        frame = pd.read_csv(csv)
        for col in TEXT_COLUMNS:
            if col in frame:
                frame[col] = frame[col].astype(object).where(frame[col].notna(), "")
        return frame
    raise ValueError(f"results directory '{results}' holds no {stem}.parquet or {stem}.csv")


def _manifests(results: Path) -> list[dict[str, Any]]:
    paths = sorted((results / "manifests").glob("*.json"))
    if not paths:
        raise ValueError(f"results directory '{results}' holds no manifests/*.json")
    return [json.loads(p.read_text(encoding="utf-8")) for p in paths]


def _setting(config: dict[str, Any], path: tuple[str, ...]) -> Any:
    value: Any = config
    for key in path:
        value = value[key]
    return value


def provenance(results: Path, runs: pd.DataFrame, scenario_runs: int) -> Provenance:
    """The run's provenance: command from :data:`RUN_RECORD`, version and git revision from
    the manifests (which must all agree), settings from the manifests' configs."""
    record_path = results / RUN_RECORD
    if not record_path.is_file():
        raise ValueError(
            f"results directory '{results}' holds no {RUN_RECORD} (written by 'hcomc reproduce' "
            "of this version); rerun 'hcomc reproduce'"
        )
    record = json.loads(record_path.read_text(encoding="utf-8"))
    manifests = _manifests(results)
    codes = sorted({(m["hcomc_version"], m["git_revision"]) for m in manifests})
    if len(codes) != 1:
        raise ValueError(
            f"results directory '{results}' mixes runs of {len(codes)} code versions {codes}; "
            "allowed: one run of 'hcomc reproduce'"
        )
    by_condition = {m["config"]["name"]: m["config"] for m in manifests}
    first = next(iter(by_condition.values()))
    settings: dict[str, Any] = {k: _setting(first, path) for k, path in SETTINGS.items()}
    settings["cav_penetration"] = {
        name: config["demand"]["cav_penetration"] for name, config in sorted(by_condition.items())
    }
    return Provenance(
        command=str(record["command"]),
        version=codes[0][0],
        revision=codes[0][1],
        seeds=int(runs["seed"].nunique()),
        seeded_runs=len(runs),
        scenario_runs=scenario_runs,
        conditions=tuple(str(c) for c in pd.unique(runs["condition"])),
        configurations=tuple(str(c) for c in pd.unique(runs["configuration"])),
        settings=settings,
    )


def _count(part: pd.DataFrame, column: str, value: Any) -> float:
    return float(part[column].eq(value).sum()) if column in part else float("nan")


def decisions(runs: pd.DataFrame) -> pd.DataFrame:
    """What every configuration decided, per condition: one row per (condition,
    configuration) with ``runs`` and counts of runs: ``merged``, ``collisions`` (summed),
    ``behind`` / ``ahead`` (VR's realised sequence relative to VMC), ``lateral`` /
    ``longitudinal`` / ``none`` / ``no_plan`` (the last plan's cooperation mode), ``gate`` /
    ``min_safety`` (Eq. 19's branch), ``fallback`` (the last plan a fallback), ``vmc_hdv``
    (VMC an HDV), ``switched`` (at least one plan switch), ``final_switch`` (the last plan
    switched), ``unmerged_fallback`` (VR never merged after its last plan fell back),
    ``lateral_equilibrium`` / ``lateral_safety_rule`` (why
    a lateral plan was admissible); ``games`` / ``games_change`` / ``games_safety_rule``
    (summed: the lane-change games played, those whose equilibrium is to change lane and those
    only the added safety rule admitted); and ``plans_per_merge`` (mean plans over runs with a
    plan), ``plan_switches`` (mean), ``decision_ms`` (median), and per last-plan mode
    (``longitudinal``, ``lateral``, ``none``) ``cd_<mode>`` and ``cd_n_<mode>``: the mean
    critical distance of those runs and the runs it is defined in. A count whose column the
    runs lack is NaN.
    """
    records = []
    for (cond, conf), part in runs.groupby(["condition", "configuration"], sort=False):
        planned = part[part["mode"].ne("")] if "mode" in part else part.iloc[:0]
        rec: dict[str, Any] = {"condition": cond, "configuration": conf, "runs": len(part)}
        rec["merged"] = _count(part, "merged", True)
        rec["collisions"] = float(part["collisions"].sum()) if "collisions" in part else np.nan
        for name, column, value in (
            ("behind", "sequence", "behind"), ("ahead", "sequence", "ahead"),
            ("lateral", "mode", "lateral"), ("longitudinal", "mode", "longitudinal"),
            ("none", "mode", "none"), ("no_plan", "mode", ""),
            ("gate", "eq19_branch", "gate"), ("min_safety", "eq19_branch", "min_safety"),
            ("fallback", "fallback", True), ("vmc_hdv", "vmc_kind", "HDV"),
            ("final_switch", "final_switch", True),
            ("lateral_equilibrium", "lateral_cause", "equilibrium"),
            ("lateral_safety_rule", "lateral_cause", "safety_rule"),
        ):  # fmt: skip
            rec[name] = _count(part, column, value)
        for column in ("games", "games_change", "games_safety_rule"):
            rec[column] = float(part[column].sum()) if column in part else np.nan
        rec["switched"] = (
            float(part["plan_switches"].gt(0).sum()) if "plan_switches" in part else np.nan
        )
        rec["unmerged_fallback"] = (
            float((part["fallback"].astype(bool) & ~part["merged"].astype(bool)).sum())
            if {"fallback", "merged"} <= set(part)
            else np.nan
        )
        rec.update(_critical_distance_by_mode(part))
        rec["plans_per_merge"] = (
            float((planned["replans"] + 1).mean()) if "replans" in part and len(planned) else np.nan
        )
        rec["plan_switches"] = (
            float(planned["plan_switches"].mean())
            if "plan_switches" in part and len(planned)
            else np.nan
        )
        rec["decision_ms"] = (
            float(planned["decision_ms"].median()) if "decision_ms" in part else np.nan
        )
        records.append(rec)
    return pd.DataFrame(records)


def _critical_distance_by_mode(part: pd.DataFrame) -> dict[str, float]:
    """``cd_<mode>`` (mean critical distance of the runs whose last plan had that mode) and
    ``cd_n_<mode>`` (how many of them define it)."""
    out = {}
    for mode in ("longitudinal", "lateral", "none"):
        if {"mode", "critical_distance"} <= set(part):
            cd = part.loc[part["mode"].eq(mode), "critical_distance"].dropna()
        else:
            cd = pd.Series(dtype=np.float64)
        out[f"cd_{mode}"] = float(cd.mean()) if len(cd) else np.nan
        out[f"cd_n_{mode}"] = float(len(cd))
    return out


def _scenario(paper_runs: pd.DataFrame) -> pd.DataFrame:
    extra = [c for c in ("collisions", "merged") if c in paper_runs]
    cols = [c for c in SCENARIO_COLUMNS if c in paper_runs]
    return paper_runs[[*cols, *extra]].reset_index(drop=True)


def digest(results: str | Path) -> Digest:
    """The :class:`Digest` of a results directory of ``hcomc reproduce``.

    Raises
    ------
    ValueError
        If a file is missing or the runs come from more than one code version.
    """
    root = Path(results)
    if not root.is_dir():
        raise ValueError(f"results directory '{root}' does not exist")
    runs = _read_table(root, "runs")
    paper_runs = _read_table(root, "paper_scenario")
    tables = pd.concat([table_summary(runs, "II"), table_summary(runs, "III")], ignore_index=True)
    return Digest(
        provenance=provenance(root, runs, len(paper_runs)),
        claims=claims(runs, paper_runs),
        tables=tables,
        decisions=decisions(runs),
        scenario=_scenario(paper_runs),
    )


def _frames(d: Digest) -> dict[str, pd.DataFrame]:
    return {
        "claims.csv": d.claims,
        "tables.csv": d.tables,
        "decisions.csv": d.decisions,
        "paper_scenario.csv": d.scenario,
    }


def save(d: Digest, data_dir: str | Path) -> list[Path]:
    """Write the digest as :data:`DATA_FILES` in ``data_dir`` (created), atomically."""
    root = Path(data_dir)
    root.mkdir(parents=True, exist_ok=True)
    paths = [root / name for name in DATA_FILES]
    with atomic_paths(*paths) as tmp:
        tmp[0].write_text(json.dumps(asdict(d.provenance), indent=2) + "\n", encoding="utf-8")
        for path, frame in zip(tmp[1:], _frames(d).values(), strict=True):
            frame.to_csv(path, index=False, na_rep=_NA, lineterminator="\n")
    return paths


def _read_csv(path: Path) -> pd.DataFrame:
    return pd.read_csv(path, keep_default_na=False, na_values=[_NA])


def load(data_dir: str | Path) -> Digest:
    """Read a digest written by :func:`save` (the same values, floats bit for bit)."""
    root = Path(data_dir)
    missing = [name for name in DATA_FILES if not (root / name).is_file()]
    if missing:
        raise ValueError(f"data directory '{root}' lacks {', '.join(missing)}")
    raw = json.loads((root / DATA_FILES[0]).read_text(encoding="utf-8"))
    raw["conditions"] = tuple(raw["conditions"])
    raw["configurations"] = tuple(raw["configurations"])
    frames = {name: _read_csv(root / name) for name in DATA_FILES[1:]}
    return Digest(
        provenance=Provenance(**raw),
        claims=frames["claims.csv"],
        tables=frames["tables.csv"],
        decisions=frames["decisions.csv"],
        scenario=frames["paper_scenario.csv"],
    )
