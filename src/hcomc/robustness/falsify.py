"""Falsification: a search for the worst case of a controller under faults, a V2X channel and
human drivers' variation.

Random seeds find rare failures slowly; the safety-validation literature searches instead
(Corso et al. 2021, "A survey of algorithms for black-box safety validation of cyber-physical
systems", JAIR 72). Here pymoo's genetic algorithm (Blank & Deb 2020) searches a box of
config values — a fault's timing and magnitude, the channel's latency and loss, the human
drivers' reaction time and time headway, the traffic's seed — for the run that minimises the
least time-to-collision of a *commanded* vehicle (one a live plan commands, in the step) with
its leader or follower; a collision involving such a vehicle scores 0, below every TTC of a
run without one.

Every candidate is a config of the scenario (its ``[v2x]``, ``[[faults]]`` and ``[shield]``
tables, :mod:`hcomc.config.impairment_tables`) and a seed, so each worst case is written as
a TOML that ``hcomc simulate CONFIG --seed S`` runs again, and as a replay.
"""

from __future__ import annotations

import copy
import itertools
import math
import os
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from hcomc.config import ConfigError, ScenarioConfig, load_config, merge_tables, nest_overrides
from hcomc.config.impairment_tables import FaultParams
from hcomc.metrics.bodies import body_pairs
from hcomc.metrics.surrogate import CLOSING_SPEED, pairs_min_ttc
from hcomc.robustness.impairments import Impairments
from hcomc.sim.log import EventKind, SimulationLog

__all__ = [
    "DEFAULT_SPACE",
    "Candidate",
    "FalsifySpec",
    "commanded_ttc",
    "evaluate",
    "falsify",
    "load_spec",
    "worst",
]

SPEC_KEYS = ("condition", "controller", "faults", "shield", "space", "overrides")
"""The keys of a search file (``hcomc falsify --space FILE``)."""

DEFAULT_FAULTS = ("brake-vmf", "aggressive-hdv")
"""The faults the default search starts from (their timing and magnitude are searched)."""

DEFAULT_SPACE: dict[str, tuple[float, float]] = {
    "seed": (0, 9999),
    "faults.0.delay": (0.0, 6.0),
    "faults.0.duration": (1.0, 6.0),
    "faults.0.decel": (4.0, 9.0),
    "faults.1.time_headway": (0.3, 1.5),
    "v2x.latency": (0.0, 0.5),
    "v2x.loss": (0.0, 0.5),
    "hdv.reaction_time_gap": (0.3, 1.5),
}
"""The default box: VMF's emergency braking (start after VR's control-zone entry [s], length
[s], deceleration [m/s²]), the key human drivers' time headway unknown to the controller [s],
the channel's latency [s] and loss [-], every human driver's reaction time (Eq. 2) [s], and
the seed."""

TIMED = {"delay": ("delay_min", "delay_max"), "duration": ("duration_min", "duration_max")}
"""``faults.K.delay`` / ``.duration`` fix a fault's drawn window: both bounds to the value."""


@dataclass(frozen=True)
class FalsifySpec:
    """What to search: the scenario (preset or file) with ``overrides``, the controller
    (any name ``hcomc run`` takes), the faults to start from (presets or tables), whether the
    shield is on, and the box (dotted config key -> (low, high); ``seed`` the traffic's)."""

    condition: str = "C2"
    controller: str = "hcomc"
    faults: tuple[str | Mapping[str, Any], ...] = DEFAULT_FAULTS
    shield: bool = False
    space: Mapping[str, tuple[float, float]] = field(default_factory=lambda: dict(DEFAULT_SPACE))
    overrides: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for key, bounds in self.space.items():
            low, high = (float(b) for b in bounds)
            if not (math.isfinite(low) and math.isfinite(high) and low <= high):
                raise ConfigError(f"space key '{key}' = {list(bounds)}: allowed: [low, high]")
        for end in (0, 1):  # every key names a config value that takes both bounds
            self.config({k: float(bounds[end]) for k, bounds in self.space.items()})

    def config(self, values: Mapping[str, float | None]) -> ScenarioConfig:
        """The scenario with the controller, the shield, the faults and ``values`` of the
        box (``None``: the key's value as given; the seed is not a config value)."""
        faults = [_table(f) for f in self.faults]
        rest: dict[str, Any] = {}
        for key, value in values.items():
            if key == "seed" or value is None:
                continue
            part = key.split(".")
            if part[0] != "faults":
                rest[key] = value
                continue
            if len(part) != 3 or not part[1].isdigit() or int(part[1]) >= len(faults):
                raise ConfigError(f"space key '{key}': allowed: faults.K.<key> for K < "
                                  f"{len(faults)}, the faults searched from")  # fmt: skip
            for name in TIMED.get(part[2], (part[2],)):
                faults[int(part[1])][name] = value
        control = {**dict(self.overrides.get("control", {})), "controller": self.controller}
        tables = {"faults": faults, "shield": {"enabled": self.shield}, "control": control}
        given = nest_overrides({k: v for k, v in self.overrides.items() if k != "control"})
        return load_config(self.condition, **merge_tables(merge_tables(given, tables),
                                                          nest_overrides(rest)))  # fmt: skip


def _table(fault: str | Mapping[str, Any]) -> dict[str, Any]:
    """A fault as a full table (a preset name resolved, a table's defaults filled in), ready
    to be changed."""
    from hcomc.config.impairment_tables import FAULTS

    if isinstance(fault, str):
        if fault not in FAULTS:
            raise ConfigError(f"fault '{fault}'; allowed: {', '.join(FAULTS)} or a table")
        return FAULTS[fault].model_dump()
    return FaultParams.model_validate(copy.deepcopy(dict(fault))).model_dump()


@dataclass(frozen=True)
class Candidate:
    """One evaluated point: its box values, seed and config, and what the run gave."""

    values: dict[str, float]
    seed: int
    config: ScenarioConfig
    least_ttc: float  # [s] of a commanded vehicle; 0 with a commanded collision
    collisions: int  # involving a commanded vehicle in a live plan
    merged: bool
    log: SimulationLog | None = None

    def row(self) -> dict[str, Any]:
        """The evaluation as a table row."""
        return {**self.values, "seed": self.seed, "least_ttc": self.least_ttc,
                "collisions_commanded": self.collisions, "merged": self.merged}  # fmt: skip


def commanded_ttc(log: SimulationLog, impaired: Impairments, n_warmup: int, every: int) -> float:
    """Least TTC [s] of the logged rows' follower-leader pairs (any lane a body occupies,
    :func:`hcomc.metrics.bodies.body_pairs`) with a vehicle that a live plan commanded in
    that step (``inf``: none closed); ``every``: steps per log row."""
    rows_of: dict[frozenset[int], list[int]] = {}
    for step, ids in impaired.commanded_at.items():
        row, off = divmod(step - n_warmup, every)
        if off == 0 and 0 <= row < log.n_steps:
            rows_of.setdefault(ids, []).append(row)
    least = math.inf
    for ids, rows in rows_of.items():
        vehicles = np.array(sorted(ids), dtype=np.int64)
        rows.sort()
        breaks = [0, *(k for k in range(1, len(rows)) if rows[k] != rows[k - 1] + 1), len(rows)]
        for a, b in itertools.pairwise(breaks):
            gap, closing = body_pairs(log, slice(rows[a], rows[b - 1] + 1), vehicles)
            least = min(least, pairs_min_ttc(gap, closing, CLOSING_SPEED))
    return least


def evaluate(
    spec: FalsifySpec, values: Mapping[str, float], *, keep_log: bool = False
) -> Candidate:
    """Run the scenario at ``values`` of the box and score it (module docstring)."""
    from hcomc.sim.engine import Simulation

    values = {k: (round(v) if k == "seed" else float(v)) for k, v in values.items()}
    config = spec.config(values)
    seed = int(values.get("seed", config.seed))
    impaired = Impairments(config.v2x, config.faults, config.shield)
    sim = Simulation(config, seed, listeners=[impaired])
    log = sim.run()
    every = round(config.log_interval / config.dt)
    collisions = impaired.collisions_commanded(log)
    least = 0.0 if collisions else commanded_ttc(log, impaired, sim.n_warmup, every)
    merged = bool(log.events_of(EventKind.MERGE).size)
    return Candidate(dict(values), seed, config, least, collisions, merged,
                     log if keep_log else None)  # fmt: skip


def falsify(
    spec: FalsifySpec, budget: int, *, search_seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
) -> list[Candidate]:  # fmt: skip
    """Search ``spec``'s box with ``budget`` runs of pymoo's genetic algorithm (population
    ``min(16, budget)``, seeded with ``search_seed``); every evaluation, in order."""
    from pymoo.algorithms.soo.nonconvex.ga import GA
    from pymoo.core.problem import ElementwiseProblem
    from pymoo.optimize import minimize

    keys = list(spec.space)
    low = np.array([spec.space[k][0] for k in keys], dtype=np.float64)
    high = np.array([spec.space[k][1] for k in keys], dtype=np.float64)
    found: list[Candidate] = []

    class Search(ElementwiseProblem):
        def __init__(self) -> None:
            super().__init__(n_var=len(keys), n_obj=1, xl=low, xu=high)

        def _evaluate(self, x: np.ndarray, out: dict[str, Any], *args: Any, **kw: Any) -> None:
            if len(found) >= budget:  # pymoo may ask past the budget within a generation
                out["F"] = math.inf
                return
            found.append(evaluate(spec, dict(zip(keys, x.tolist(), strict=True))))
            if progress is not None:
                progress(len(found), budget)
            out["F"] = found[-1].least_ttc

    pop = max(2, min(16, budget))
    minimize(Search(), GA(pop_size=pop, eliminate_duplicates=True), ("n_evals", budget),
             seed=search_seed, verbose=False)  # fmt: skip
    return found


def worst(found: list[Candidate], k: int) -> list[Candidate]:
    """The ``k`` evaluations with the least scores (collisions first), ties by order."""
    order = sorted(range(len(found)), key=lambda i: (found[i].least_ttc, -found[i].collisions, i))
    return [found[i] for i in order[:k]]


def load_spec(path: str | os.PathLike[str], **given: Any) -> FalsifySpec:
    """A search file: TOML with any of :data:`SPEC_KEYS` (``space`` a table of
    ``"dotted.key" = [low, high]``, ``faults`` presets or tables, ``overrides`` config keys);
    ``given`` (the command line's, not None) take precedence. ConfigError naming a bad key."""
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"search file '{path}': {exc}") from None
    unknown = sorted(set(data) - set(SPEC_KEYS))
    if unknown:
        raise ConfigError(f"search file '{path}': unknown key '{unknown[0]}'; allowed: "
                          f"{', '.join(SPEC_KEYS)}")  # fmt: skip
    space = data.get("space", DEFAULT_SPACE)
    if not isinstance(space, dict) or not all(
        isinstance(v, list) and len(v) == 2 for v in space.values()
    ):
        raise ConfigError(f"search file '{path}': key 'space': allowed: a table of "
                          '"dotted.key" = [low, high]')  # fmt: skip
    data["space"] = {k: (float(v[0]), float(v[1])) for k, v in space.items()}
    if "faults" in data:
        data["faults"] = tuple(data["faults"])
    return FalsifySpec(**{**data, **{k: v for k, v in given.items() if v is not None}})
