"""The lane of an FCD sample on a lane line is the lane the vehicle moves into (the engine's
rule: a changing vehicle's lane switches when its centre reaches the lane line)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.road import Lane
from hcomc.sumo.fcd import read_fcd, write_fcd

CONFIG = load_config("C1")  # lane width 3.75 m: the lane lines at y = -1.875 and 1.875 m
W = CONFIG.road.lane_width


def _fcd(path: Path, tracks: dict[str, list[float]], angle: float = 90.0) -> Path:
    """An FCD file of vehicles at ``x = 500 + 20 t`` with lateral positions ``tracks[id]``,
    one timestep every 0.1 s from the end of the warm-up."""
    steps = []
    for k in range(len(next(iter(tracks.values())))):
        t = CONFIG.warmup + 0.1 * k
        cars = "".join(
            f'<vehicle id="{vid}" x="{500.0 + 2.0 * k}" y="{ys[k]}" angle="{angle}" '
            f'type="cav" speed="20" acceleration="0"/>'
            for vid, ys in tracks.items()
        )
        steps.append(f'<timestep time="{t:.1f}">{cars}</timestep>')
    path.write_text(f"<fcd-export>{''.join(steps)}</fcd-export>")
    return path


@pytest.mark.parametrize(
    ("ys", "lanes"),
    [
        ([0.0, 0.5 * W, W], [1, 2, 2]),  # lane 1 -> 2: on the line it is in lane 2 already
        ([W, 0.5 * W, 0.0], [2, 1, 1]),  # lane 2 -> 1
        ([-W, -0.5 * W, 0.0], [0, 1, 1]),  # the merge: ramp -> lane 1
        ([0.2 * W, 0.5 * W, 0.5 * W, 0.8 * W], [1, 2, 2, 2]),  # lingering on the line
    ],
)
def test_a_sample_on_a_lane_line_is_in_the_lane_moved_into(
    ys: list[float], lanes: list[int], tmp_path: Path
) -> None:
    log, ids = read_fcd(_fcd(tmp_path / "f.xml", {"v0": ys}), CONFIG)
    assert log.lane[:, ids["v0"]].tolist() == lanes


def test_without_lateral_motion_the_heading_decides(tmp_path: Path) -> None:
    """A vehicle seen only on the lane line: its heading (navigation angle below 90 degrees:
    moving to the left, +y) tells the lane it moves into."""
    left = read_fcd(_fcd(tmp_path / "l.xml", {"v0": [0.5 * W] * 3}, angle=85.0), CONFIG)[0]
    right = read_fcd(_fcd(tmp_path / "r.xml", {"v0": [0.5 * W] * 3}, angle=95.0), CONFIG)[0]
    assert left.lane[:, 0].tolist() == [Lane.MAIN_2] * 3
    assert right.lane[:, 0].tolist() == [Lane.MAIN_1] * 3


def test_engine_lane_change_through_the_line_round_trips(tmp_path: Path) -> None:
    """A log in which the engine's lane switch happens exactly on the lane line (y = W / 2,
    lane 2) reads back with the same lanes, sample for sample."""
    from hcomc.sim.log import SimulationLog

    ys = np.array([0.0, 0.25 * W, 0.5 * W, 0.75 * W, W])
    lanes = np.array([1, 1, 2, 2, 2])
    log = SimulationLog.allocate(5, 1, dt=0.1, kind=np.ones(1, dtype=int), length=np.full(1, 5.0),
                                 width=np.full(1, 1.8), meta={})  # fmt: skip
    for k in range(5):
        log.record(k, 0.1 * k, np.array([500.0 + 2.0 * k]), ys[k : k + 1], np.array([20.0]),
                   np.zeros(1), np.array([0.1]), lanes[k : k + 1], np.ones(1, bool))  # fmt: skip
    back, _ = read_fcd(write_fcd(log, tmp_path / "e.xml", CONFIG), CONFIG)
    assert back.lane[:, 0].tolist() == lanes.tolist()
