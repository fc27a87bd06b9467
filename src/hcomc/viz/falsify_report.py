"""What ``hcomc falsify`` writes: per searched setting (controller, shield) its evaluations,
its worst cases as configs and replays; over all settings a summary, and the section of
docs/robustness.md generated from it.

A search's directory holds ``falsify.json`` (the specs, budget, search seed, version and
revision, and per setting its worst cases) and ``summary.csv`` (one row per setting: runs,
runs with a commanded collision, the least TTC found and the seed and config of that case);
each setting's subdirectory holds ``evaluations.csv`` and ``worst-K.toml`` / ``worst-K.html``.
"""

from __future__ import annotations

import json
import math
import re
import shutil
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import pandas as pd

import hcomc
from hcomc.config import ConfigError, config_to_toml
from hcomc.robustness.falsify import Candidate, FalsifySpec, evaluate, worst
from hcomc.sim.manifest import atomic_paths, git_revision, write_json_atomic

__all__ = ["MARKERS", "Searched", "generated_part", "publish", "setting_dir", "write_search"]

MARKERS = ("<!-- falsification: begin -->", "<!-- falsification: end -->")
"""The comments around the generated section of docs/robustness.md."""


def setting_dir(out: Path, spec: FalsifySpec) -> Path:
    """A setting's subdirectory: ``<controller>-shield-<on|off>``."""
    name = re.sub(r"[^\w.-]+", "_", spec.controller)
    return out / f"{name}-shield-{'on' if spec.shield else 'off'}"


def _finite(row: dict[str, Any]) -> dict[str, Any]:
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
            for k, v in row.items()}  # fmt: skip


class Searched:
    """One setting's search: its spec, every evaluation, and the worst ``top`` written out."""

    def __init__(self, spec: FalsifySpec, found: list[Candidate], top: int) -> None:
        self.spec, self.found, self.cases = spec, found, worst(found, top)

    def write(self, folder: Path) -> list[dict[str, Any]]:
        """Evaluations, and each worst case as a config (its seed inside) and a replay."""
        from hcomc.viz.replay import write_replay

        folder.mkdir(parents=True, exist_ok=True)
        pd.DataFrame([c.row() for c in self.found]).to_csv(folder / "evaluations.csv", index=False)
        records = []
        for k, case in enumerate(self.cases, start=1):
            config = case.config.model_copy(update={"seed": case.seed})
            (folder / f"worst-{k}.toml").write_text(config_to_toml(config), encoding="utf-8")
            again = evaluate(self.spec, case.values, keep_log=True)  # the run, with its log
            title = f"worst case {k}: {self.spec.controller}, seed {case.seed}"
            write_replay(folder / f"worst-{k}.html", [again.log], titles=[title])
            records.append({**_finite(case.row()), "config": f"worst-{k}.toml",
                            "replay": f"worst-{k}.html"})  # fmt: skip
        return records

    def summary(self, folder: str) -> dict[str, Any]:
        """The setting's row of ``summary.csv``."""
        first = self.cases[0]
        return {
            "controller": self.spec.controller, "shield": self.spec.shield,
            "runs": len(self.found),
            "runs_with_collision": sum(c.collisions > 0 for c in self.found),
            "least_ttc": first.least_ttc, "seed": first.seed,
            "config": f"{folder}/worst-1.toml",
        }  # fmt: skip


def write_search(out: Path, searches: Sequence[Searched], search_seed: int, command: str) -> None:
    """Every setting's directory, ``summary.csv`` and ``falsify.json`` under ``out``."""
    settings, rows = [], []
    for s in searches:
        folder = setting_dir(out, s.spec)
        worst_cases = s.write(folder)
        spec = {**asdict(s.spec), "space": {k: list(v) for k, v in s.spec.space.items()}}
        settings.append({"spec": spec, "folder": folder.name, "worst": worst_cases})
        rows.append(s.summary(folder.name))
    with atomic_paths(out / "summary.csv") as (tmp,):
        pd.DataFrame(rows).to_csv(tmp, index=False)
    record = {"command": command, "budget": len(searches[0].found),
              "search_seed": search_seed, "version": hcomc.__version__,
              "revision": git_revision(), "settings": settings}  # fmt: skip
    write_json_atomic(out / "falsify.json", json.loads(json.dumps(record, default=str)))


def _shield_sentence(summary: pd.DataFrame) -> str:
    """What the shield did to the worst case found, per controller searched both ways."""
    by = summary.pivot_table(index="controller", columns="shield", values="least_ttc",
                             sort=False)  # fmt: skip
    if not {False, True} <= set(by.columns):
        return ""
    larger = [c for c in by.index if by.loc[c, True] > by.loc[c, False]]
    other = [c for c in by.index if c not in larger]
    text = f" With the shield the least TTC found is larger for {', '.join(larger) or 'none'}"
    return text + (f", not for {', '.join(other)}." if other else ".")


def _on(shield: object) -> str:
    return "on" if bool(shield) else "off"


def generated_part(summary: pd.DataFrame, record: dict[str, Any]) -> str:
    """The section of docs/robustness.md: the worst case each setting's search found."""
    stamp = f"hcomc {record['version']}, revision {record['revision']}"
    lines = [
        MARKERS[0],
        f"<!-- generated by `{record['command']}`; {stamp} -->",
        "",
        "| controller | shield | runs | runs with a commanded collision | least TTC found [s] "
        "| seed | reproduce |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in summary.to_dict("records"):
        ttc = "collision" if row["least_ttc"] == 0 else f"{row['least_ttc']:.2f}"
        lines.append(
            f"| {row['controller']} | {_on(row['shield'])} | {row['runs']} | "
            f"{row['runs_with_collision']} | {ttc} | {row['seed']} | "
            f"`hcomc simulate docs/data/falsify/{row['config']}` |"
        )
    hit = summary[summary.runs_with_collision > 0]
    names = [f"{c} (shield {_on(s)})" for c, s in zip(hit.controller, hit.shield, strict=True)]
    if names:
        said = f"The search found a collision of a commanded vehicle for {', '.join(names)}."
    else:
        said = (f"No search found a collision of a commanded vehicle in "
                f"{summary.runs.iloc[0]} runs per setting.")  # fmt: skip
    lines += ["", said + _shield_sentence(summary), MARKERS[1]]
    return "\n".join(lines)


def publish(out: Path, docs: Path) -> Path:
    """Write the search in ``out`` into ``docs/robustness.md``'s generated section, with its
    summary, record and each setting's worst case under ``docs/data/falsify``."""
    target = docs / "robustness.md"
    text = target.read_text(encoding="utf-8") if target.exists() else ""
    if MARKERS[0] not in text or MARKERS[1] not in text:
        raise ConfigError(f"{target} has no '{MARKERS[0]}' ... '{MARKERS[1]}' section to replace")
    summary = pd.read_csv(out / "summary.csv")
    record = json.loads((out / "falsify.json").read_text(encoding="utf-8"))
    data = docs / "data" / "falsify"
    data.mkdir(parents=True, exist_ok=True)
    for name in ("summary.csv", "falsify.json"):
        shutil.copyfile(out / name, data / name)
    for config in summary.config:
        (data / config).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(out / config, data / config)
    head, rest = text.split(MARKERS[0], 1)
    with atomic_paths(target) as (tmp,):
        tmp.write_text(head + generated_part(summary, record) + rest.split(MARKERS[1], 1)[1])
    return target
