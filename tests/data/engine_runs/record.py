"""Record the reference runs of ``tests/scenario/test_recorded_runs.py`` from the present engine.

    python tests/data/engine_runs/record.py tests/data/engine_runs

Cases: C1-C5 with no controller, with FIFO, with Game and with HCOMC (NSGA-II), C4 with a ramp
flow and the platoon scenario, seed 0. Per case: the float64 state (x, v, y, lane) at the end
of the run, the logged x and v of every 10th row and the event table; ``recorded.json`` says
which hcomc version and git revision recorded them. Re-record only after a change of
behaviour that is intended and stated; a change that claims to keep behaviour leaves them.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from hcomc.config import load_config
from hcomc.sim.engine import Simulation
from hcomc.sim.manifest import git_revision

CASES = {
    **{
        f"{c}-{ctrl}": (c, {"control": {"controller": ctrl}})
        for c in ("C1", "C2", "C3", "C4", "C5")
        for ctrl in ("none", "fifo", "game", "hcomc")
    },
    "C4-flow-none": ("C4", {"control": {"controller": "none"}, "demand": {"ramp": "flow"}}),
    "platoon": ("platoon", {}),
}


def run(preset: str, overrides: dict[str, Any]) -> dict[str, np.ndarray]:
    """What is recorded of one case, seed 0: the arrays of its ``.npz`` file."""
    sim = Simulation(load_config(preset, **overrides), 0)
    log = sim.run()
    events = np.asarray(log.events.tolist(), dtype=np.float64).reshape(-1, 6)
    return {
        "x": sim.x, "y": sim.y, "v": sim.v, "lane": sim.lane,
        "log_x": log.x[::10], "log_v": log.v[::10], "events": events,
    }  # fmt: skip


def main(out: Path) -> None:
    import hcomc

    out.mkdir(parents=True, exist_ok=True)
    for name, case in CASES.items():
        arrays = run(*case)
        np.savez_compressed(out / f"{name}.npz", **arrays)
        print(name, arrays["log_x"].shape, len(arrays["events"]))
    stamp = {"version": hcomc.__version__, "revision": git_revision(), "seed": 0}
    (out / "recorded.json").write_text(json.dumps(stamp, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
