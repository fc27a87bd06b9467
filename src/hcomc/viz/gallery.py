"""The showcase of a reproduction run: one recorded scene and the stamped gallery images.

``hcomc reproduce`` records one scene beside its results (:func:`record_scene`): the
condition of the paper's Fig. 2 at the first seed, simulated with FIFO, Game and HCOMC as the
runs were (their logs), and the first merge decision of HCOMC with NSGA-II, PSO and SA (their
plan reports). :func:`write_gallery` draws from that scene and the runs table the images the
README shows, through the figure functions ``hcomc plot`` and ``hcomc animate`` use, each
stamped in a bottom corner (and in its file metadata) with the hcomc version and git
revision of the run. Nothing is simulated there.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hcomc.sim.manifest import atomic_paths, write_json_atomic

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from hcomc.sim.log import SimulationLog

__all__ = [
    "GALLERY",
    "SCENE_CONFIGURATIONS",
    "SCENE_DIR",
    "read_stamp",
    "record_scene",
    "write_gallery",
]

SCENE_DIR = "scene"
"""Subdirectory of a results directory holding the recorded scene."""
REPLAY_FILE = "replay.html"
"""The scene's interactive replay, beside its logs."""

SCENE_CONFIGURATIONS = ("FIFO", "Game", "HCOMC")
"""Configurations simulated for the scene (one log each, ``<label>.npz``)."""

PARETO_CONFIGURATIONS = {"nsga2": "HCOMC", "pso": "HCOMC-PSO", "sa": "HCOMC-SA"}
"""Optimiser -> configuration whose first decision the scene's ``plans.json`` records."""

GALLERY = (
    "contour.png",
    "timespace.png",
    "trajectories.png",
    "pareto.png",
    "metrics.png",
    "animation.gif",
)
"""The images :func:`write_gallery` writes, by file name."""

ANIMATION_MARGIN = (2.0, 8.0)
"""The animation shows the first plan's time minus the first and VR's merge plus the second
value [s] (the whole log when either is unknown)."""

_STAMP_KEY = "Description"  # PNG text chunk holding the stamp
_DPI = 150


def _first_decision(condition: str, seed: int, overrides: dict[str, Any]) -> dict[str, Any]:
    """The plan report of the first merge decision of a configuration's run."""
    from hcomc.config import load_config
    from hcomc.control.report import plan_report
    from hcomc.sim.engine import Simulation

    sim = Simulation(load_config(condition, **overrides), seed)
    plan = sim.run_until_plan()
    if plan is None:
        raise ValueError(
            f"no ramp vehicle entered the control zone in '{condition}', seed {seed}: the "
            "scene has no decision to show; allowed: a condition with ramp demand"
        )
    return plan_report(sim, plan)


def record_scene(
    out_dir: str | Path, condition: str, seed: int, overrides: dict[str, Any] | None = None
) -> bytes:
    """Simulate and save the scene of a reproduction run; return its contour maps as PNG.

    Writes ``out_dir/scene/``: ``FIFO.npz``, ``Game.npz`` and ``HCOMC.npz`` (the logs of
    :func:`hcomc.viz.inputs.controller_logs` with the runs' config ``overrides``),
    ``plans.json`` (optimiser -> plan report of the first decision, the input of ``hcomc
    plot plans.json --kind pareto``), ``replay.html`` (the three runs side by side in the
    interactive replay, :func:`hcomc.viz.replay.write_replay`) and ``scene.json`` (condition
    and seed). A
    self-contained task that ``hcomc reproduce`` hands to a worker process; the PNG is the
    report's Fig. 2.
    """
    from hcomc.experiments.runner import configuration_overrides
    from hcomc.viz.figures import contour_figure
    from hcomc.viz.inputs import controller_logs
    from hcomc.viz.page import figure_png
    from hcomc.viz.replay import write_replay

    settings = dict(overrides or {})
    logs = controller_logs(condition, seed=seed, overrides=settings)
    scene = Path(out_dir) / SCENE_DIR
    scene.mkdir(parents=True, exist_ok=True)
    for label, log in logs.items():
        log.save(scene / f"{label}.npz")
    write_replay(scene / REPLAY_FILE, list(logs.values()), list(logs))
    reports = {
        opt: _first_decision(condition, seed, configuration_overrides(label, settings))
        for opt, label in PARETO_CONFIGURATIONS.items()
    }
    write_json_atomic(scene / "plans.json", reports)
    write_json_atomic(scene / "scene.json", {"condition": condition, "seed": seed})
    return figure_png(contour_figure(logs))


def _stamp_figure(fig: Figure, stamp: str) -> None:
    fig.text(0.998, 0.002, stamp, ha="right", va="bottom", fontsize=6, color="0.4")


def _save_png(fig: Figure, path: Path, stamp: str) -> Path:
    """Write a stamped figure as PNG (the stamp also in its ``Description`` text chunk)."""
    _stamp_figure(fig, stamp)
    with atomic_paths(path) as (tmp,), tmp.open("wb") as fh:
        fig.savefig(fh, format="png", dpi=_DPI, metadata={"Software": None, _STAMP_KEY: stamp})
    return path


def _stamp_gif(path: Path, stamp: str) -> None:
    """Draw the stamp into every frame's bottom-left corner (the bottom-right one holds the
    scene's lateral-scale note) and store it as the GIF's comment, keeping the frame
    durations and looping."""
    from PIL import Image, ImageDraw, ImageSequence

    with Image.open(path) as im:
        info = {"duration": im.info.get("duration", 100), "loop": im.info.get("loop", 0)}
        frames = []
        for frame in ImageSequence.Iterator(im):
            rgb = frame.convert("RGB")
            draw = ImageDraw.Draw(rgb)
            _, top, _, bottom = draw.textbbox((0, 0), stamp)
            draw.text((4, rgb.size[1] - (bottom - top) - 4), stamp, fill=(90, 90, 90))
            frames.append(rgb.quantize(256, method=Image.Quantize.FASTOCTREE))
    with atomic_paths(path) as (tmp,):
        frames[0].save(
            tmp, format="GIF", save_all=True, append_images=frames[1:], comment=stamp, **info
        )


def _animation_range(log: SimulationLog) -> tuple[float, float] | None:
    from hcomc.viz.common import key_group, key_time, merge_time

    t0 = key_time(log)
    t1, _ = merge_time(log, key_group(log).get("VR", -1))
    if not (math.isfinite(t0) and math.isfinite(t1)):
        return None
    return t0 - ANIMATION_MARGIN[0], t1 + ANIMATION_MARGIN[1]


def write_gallery(results: str | Path, img_dir: str | Path, stamp: str) -> list[Path]:
    """Draw :data:`GALLERY` into ``img_dir`` from a results directory: the contour maps of
    the scene's three logs (paper Fig. 2), the time-space diagram, merge trajectories and
    animation of its HCOMC run, the Pareto set of its first decisions and the metrics of the
    runs table, each stamped with ``stamp``.

    Raises
    ------
    ValueError
        If the results directory lacks the runs table or the scene.
    """
    from hcomc.viz.animation import animate
    from hcomc.viz.figures import (
        contour_figure,
        metrics_figure,
        pareto_figure,
        timespace_figure,
        trajectories_figure,
    )
    from hcomc.viz.inputs import load_log, load_reports, load_runs

    root, out = Path(results), Path(img_dir)
    scene = root / SCENE_DIR
    if not (scene / "plans.json").is_file():
        raise ValueError(
            f"results directory '{root}' holds no {SCENE_DIR}/plans.json: the scene "
            "'hcomc reproduce' records; rerun 'hcomc reproduce'"
        )
    logs = {label: load_log(scene / f"{label}.npz") for label in SCENE_CONFIGURATIONS}
    out.mkdir(parents=True, exist_ok=True)
    hcomc = logs["HCOMC"]
    figures: Mapping[str, Any] = {
        "contour.png": lambda: contour_figure(logs),
        "timespace.png": lambda: timespace_figure(hcomc),
        "trajectories.png": lambda: trajectories_figure(hcomc),
        "pareto.png": lambda: pareto_figure(load_reports([scene / "plans.json"])),
        "metrics.png": lambda: metrics_figure(load_runs(root)),
    }
    written = [_save_png(build(), out / name, stamp) for name, build in figures.items()]
    gif = animate(hcomc, out / "animation.gif", t_range=_animation_range(hcomc))
    _stamp_gif(gif, stamp)
    return [*written, gif]


def read_stamp(path: str | Path) -> str:
    """The stamp of a gallery image (PNG text chunk or GIF comment), "" if it has none."""
    from PIL import Image

    with Image.open(path) as im:
        value = im.info.get("comment" if im.format == "GIF" else _STAMP_KEY, "")
    if isinstance(value, bytes):
        return value.decode("utf-8")
    return str(value or "")
