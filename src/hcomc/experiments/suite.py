"""Benchmark suites: named, versioned sets of merge scenarios every controller is run on.

A :class:`Suite` is what a comparison of merge controllers cites ("merge-v1"): a list of
:class:`Cell` s, each a condition preset plus fixed overrides, and a default number of seeds.
The cells are defaults of the benchmark, never tuned per controller. A suite never changes
once published: a changed cell is a new version (``merge-v2``), so that two results citing
the same suite name were run on the same scenarios. ``hcomc compare`` records the suite's
name in its results and refuses to mix runs of another version.

``merge-v1`` holds the paper's five Table I conditions as published (C1-C5) and three harder
held-out cells the paper does not test: denser mainline traffic, few CAVs, and a continuous
ramp demand instead of one key merge.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

from hcomc.config import ConfigError, ScenarioConfig, load_config, merge_tables


@dataclass(frozen=True)
class Cell:
    """One scenario of a suite: a condition preset (or TOML file) with nested overrides.

    ``id`` is what results call the cell (their ``condition`` column) and what
    ``--conditions`` selects; ``overrides`` are nested as :func:`load_config` takes them
    (``{"demand": {"cav_penetration": 0.2}}``).
    """

    id: str
    condition: str
    overrides: dict[str, Any] = field(default_factory=dict, hash=False)
    description: str = ""

    def config(self, **extra: Any) -> ScenarioConfig:
        """The cell's scenario, with ``extra`` (nested) overrides on top of the cell's."""
        return load_config(self.condition, **merge_tables(self.overrides, extra))

    def overrides_text(self) -> str:
        """The overrides as dotted ``key = value`` pairs ("—" for none), for tables."""
        pairs = [f"{key} = {json.dumps(value)}" for key, value in _dotted(self.overrides)]
        return ", ".join(pairs) or "—"


@dataclass(frozen=True)
class Suite:
    """A versioned benchmark: its cells, in display order, and the default seeds per cell."""

    id: str
    version: int
    cells: tuple[Cell, ...]
    seeds: int
    description: str = ""

    @property
    def name(self) -> str:
        """What results cite: ``<id>-v<version>``."""
        return f"{self.id}-v{self.version}"

    def cell(self, cell_id: str) -> Cell:
        """The cell named ``cell_id`` (case-insensitive); ConfigError if there is none."""
        for cell in self.cells:
            if cell.id.lower() == cell_id.strip().lower():
                return cell
        raise ConfigError(
            f"option '--conditions': '{cell_id}' is not a cell of suite '{self.name}'; "
            f"allowed: {', '.join(c.id for c in self.cells)}, or ranges such as C1..C5"
        )

    def select(self, text: str | None) -> tuple[Cell, ...]:
        """The cells ``text`` names: comma-separated ids and ranges ``FIRST..LAST`` (in suite
        order, both ends included), case-insensitive; every cell when ``text`` is None or
        empty. Each cell once, in the order first named."""
        if text is None or not text.strip():
            return self.cells
        chosen: dict[str, Cell] = {}
        for item in (part.strip() for part in text.split(",")):
            if not item:
                raise ConfigError(f"option '--conditions' = '{text}': an empty cell id")
            first, dots, last = item.partition("..")
            if not dots:
                cell = self.cell(item)
                chosen.setdefault(cell.id, cell)
                continue
            i, j = self.cells.index(self.cell(first)), self.cells.index(self.cell(last))
            if i > j:
                raise ConfigError(
                    f"option '--conditions' = '{item}': {self.cells[i].id} comes after "
                    f"{self.cells[j].id} in suite '{self.name}'; allowed: FIRST..LAST in the "
                    f"order {', '.join(c.id for c in self.cells)}"
                )
            for cell in self.cells[i : j + 1]:
                chosen.setdefault(cell.id, cell)
        return tuple(chosen.values())

    def markdown_table(self) -> str:
        """The cells as a Markdown table (id, condition, overrides, description): what the
        documentation shows, generated here so that it cannot drift from the code."""
        lines = ["| Cell | Condition | Overrides | Description |", "|---|---|---|---|"]
        for cell in self.cells:
            overrides = cell.overrides_text()
            shown = overrides if overrides == "—" else f"`{overrides}`"
            lines.append(f"| `{cell.id}` | `{cell.condition}` | {shown} | {cell.description} |")
        return "\n".join(lines) + "\n"


def _dotted(tree: dict[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    """Leaf ``(dotted.key, value)`` pairs of nested overrides, in insertion order."""
    pairs: list[tuple[str, Any]] = []
    for key, value in tree.items():
        if isinstance(value, dict):
            pairs += _dotted(value, f"{prefix}{key}.")
        else:
            pairs.append((f"{prefix}{key}", value))
    return pairs


MERGE_V1 = Suite(
    id="merge",
    version=1,
    seeds=30,
    description="the paper's Table I conditions and three harder held-out cells",
    cells=(
        Cell("C1", "C1", {}, "Table I condition 1: headways 5 s / 5 s, 90 % CAVs"),
        Cell("C2", "C2", {}, "Table I condition 2: headways 5 s / 7 s, 90 % CAVs"),
        Cell("C3", "C3", {}, "Table I condition 3: headways 5 s / 3 s, 90 % CAVs"),
        Cell("C4", "C4", {}, "Table I condition 4: headways 5 s / 5 s, 60 % CAVs"),
        Cell("C5", "C5", {}, "Table I condition 5: headways 5 s / 5 s, 30 % CAVs"),
        Cell(
            "H1-dense",
            "C2",
            {"demand": {"mean_headway_main_1": 3.0, "mean_headway_main_2": 4.0}},
            "denser traffic: C2 with headways 3 s / 4 s (smaller gaps for VR, less room in "
            "lane 2 for lateral cooperation)",
        ),
        Cell(
            "H2-lowpen",
            "C1",
            {"demand": {"cav_penetration": 0.2}},
            "low CAV penetration: C1 with 20 % CAVs (VMC and its neighbours are mostly human "
            "drivers that no controller commands)",
        ),
        Cell(
            "H3-flow",
            "C1",
            {"warmup": 0.0, "demand": {"ramp": "flow", "ramp_mean_headway": 12.0}},
            "continuous ramp demand: C1 with a ramp vehicle every 12 s on average instead of "
            "one key merge; the metrics are of the first ramp vehicle's merge, with the others "
            "merging around it (no warm-up: a flow starts with it, and the first merge would "
            "fall in the unmeasured warm-up)",
        ),
    ),
)
"""The first merge benchmark."""

SUITES: dict[str, Suite] = {suite.name: suite for suite in (MERGE_V1,)}
"""Every published suite by name (``merge-v1``); a name never changes meaning."""

LATEST = MERGE_V1.name
"""The suite ``hcomc compare`` uses unless told otherwise."""


def suite_named(name: str) -> Suite:
    """The suite called ``name`` (case-insensitive); ConfigError naming the allowed ones."""
    for key, suite in SUITES.items():
        if key.lower() == name.strip().lower():
            return suite
    raise ConfigError(f"option '--suite' = '{name}': no such suite; allowed: {', '.join(SUITES)}")


__all__ = ["LATEST", "MERGE_V1", "SUITES", "Cell", "Suite", "suite_named"]
