"""Fingerprints of 60 runs of the engine: did a change keep hcomc's behaviour bit for bit?

Runs Conditions C1-C5 with no controller, FIFO, Game and HCOMC with each of its three
optimisers (NSGA-II, PSO, SA), seeds 0 and 1, and prints one SHA-256 per run over the
float64 end state (x, y, v, lane, active), the logged trajectories and the event table, then
one over all runs. A restructuring that claims unchanged behaviour runs it on the revisions
before and after (the same machine: the digests are bit-level, so another CPU or C library
may differ in the last bit) and compares the lines::

    python benchmarks/fingerprint.py > after.txt
    PYTHONPATH=<checkout of the earlier revision>/src python benchmarks/fingerprint.py > before.txt
    diff before.txt after.txt

It uses only ``hcomc.config.load_config`` and ``hcomc.sim.engine.Simulation``, so it runs on
earlier revisions too. ``--json`` prints the digests as one JSON object.
"""

from __future__ import annotations

import argparse
import hashlib
import json
from collections.abc import Iterator
from typing import Any

import numpy as np

from hcomc.config import load_config
from hcomc.sim.engine import Simulation

CONDITIONS = ("C1", "C2", "C3", "C4", "C5")
SETUPS: dict[str, dict[str, Any]] = {
    "none": {"controller": "none"},
    "fifo": {"controller": "fifo"},
    "game": {"controller": "game"},
    "hcomc-nsga2": {"controller": "hcomc", "optimizer": "nsga2"},
    "hcomc-pso": {"controller": "hcomc", "optimizer": "pso"},
    "hcomc-sa": {"controller": "hcomc", "optimizer": "sa"},
}
SEEDS = (0, 1)


def cases() -> Iterator[tuple[str, str, dict[str, Any], int]]:
    """(name, condition, control table, seed) of every fingerprinted run."""
    for condition in CONDITIONS:
        for setup, control in SETUPS.items():
            for seed in SEEDS:
                yield f"{condition}-{setup}-{seed}", condition, control, seed


def digest(condition: str, control: dict[str, Any], seed: int) -> str:
    """SHA-256 of one run's end state, logged trajectories and events."""
    sim = Simulation(load_config(condition, control=control), seed)
    log = sim.run()
    h = hashlib.sha256()
    for array in (sim.x, sim.y, sim.v, sim.lane, sim.active, log.x, log.y, log.v, log.lane):
        h.update(np.ascontiguousarray(array).tobytes())
    h.update(np.asarray(log.events.tolist(), dtype=np.float64).tobytes())
    return h.hexdigest()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="one JSON object")
    parser.add_argument("--only", default="", help="comma-separated run names (default: all)")
    args = parser.parse_args()
    only = set(filter(None, args.only.split(",")))
    digests = {
        name: digest(c, ctl, seed) for name, c, ctl, seed in cases() if not only or name in only
    }
    digests["all"] = hashlib.sha256("".join(digests.values()).encode()).hexdigest()
    if args.json:
        print(json.dumps(digests, indent=1))
    else:
        for name, value in digests.items():
            print(f"{name:<20} {value}")


if __name__ == "__main__":
    main()
