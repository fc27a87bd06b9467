"""Record the reference trajectories of the numpy simulation step (run at revision 58b31af,
the last numpy step; ``PYTHONPATH=<that checkout>/src python make_reference.py OUT_DIR``).

The runs include the controllers' decisions, so a reference holds only while the controller's
decisions are those of that revision: HCOMC's cases were dropped when its planning changed
(Eq. 17 at the decision, the commitment rule); the hand-over of its plans between Python and
the compiled loop is checked by ``tests/scenario/test_compiled_plans.py``. C5 with FIFO was
dropped when a plan stopped holding a CAV VR it does not command on the ramp: in that run
FIFO's plans command no vehicle, and its CAV VR now merges by gap acceptance at once.

Per case: the float64 state (x, v, y, lane) at the end of the run, the logged x and v of
every 10th row and the event table, which ``tests/scenario/test_compiled_step.py`` compares
with the compiled step.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from hcomc.config import load_config
from hcomc.sim.engine import Simulation

CASES = {
    **{
        f"{c}-{ctrl}": (c, {"control": {"controller": ctrl}})
        for c in ("C1", "C2", "C3", "C4", "C5")
        for ctrl in ("none", "fifo")
        if (c, ctrl) != ("C5", "fifo")
    },
    "C4-flow-none": ("C4", {"control": {"controller": "none"}, "demand": {"ramp": "flow"}}),
    "platoon": ("platoon", {}),
}


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    for name, (preset, overrides) in CASES.items():
        sim = Simulation(load_config(preset, **overrides), 0)
        log = sim.run()
        events = np.asarray(log.events.tolist(), dtype=np.float64).reshape(-1, 6)
        np.savez_compressed(
            out / f"{name}.npz", x=sim.x, v=sim.v, y=sim.y, lane=sim.lane,
            log_x=log.x[::10], log_v=log.v[::10], events=events,
        )  # fmt: skip
        print(name, log.x.shape, len(events))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
