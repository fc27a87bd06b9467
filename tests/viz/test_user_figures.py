"""Figures a new user meets: shared heatmap scales, n per cell, platoon time-space plots,
uncontrolled trajectories, explained gaps and single-numbered report captions."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import LineCollection

from hcomc.config import load_config
from hcomc.sim.engine import simulate
from hcomc.viz.figures import metrics_figure, timespace_figure, trajectories_figure
from hcomc.viz.page import figure_png
from hcomc.viz.report import write_report
from hcomc.viz.sweep import heatmap_figure


def _sweep_table(missing: bool = False) -> pd.DataFrame:
    """Synthetic sweep rows: 2 headway pairs x 2 penetrations x 3 configurations x 3 seeds."""
    rows = []
    offset = {"FIFO": 0.0, "Game": 20.0, "HCOMC": 40.0}
    for h2, pen, conf, seed in itertools.product((3.0, 5.0), (0.3, 0.9), offset, range(3)):
        value = 10.0 * h2 + 100.0 * pen + offset[conf] + seed
        if missing and (conf, h2, pen, seed) == ("HCOMC", 3.0, 0.3, 2):
            value = np.nan
        rows.append({"mean_headway_main_1": 5.0, "mean_headway_main_2": h2,
                     "cav_penetration": pen, "configuration": conf, "seed": seed,
                     "critical_distance": value})  # fmt: skip
    return pd.DataFrame(rows)


def test_heatmap_shares_one_colour_scale_across_controllers():
    fig = heatmap_figure(_sweep_table(), "critical_distance")
    images = [ax.images[0] for ax in fig.axes if ax.images]
    plain = [im for im, ax in zip(images, fig.axes, strict=False)
             if not ax.get_title().startswith("HCOMC vs")]  # fmt: skip
    diffs = [im for im in images if im not in plain]
    assert len(plain) == 3
    assert len(diffs) == 2
    assert len({im.get_clim() for im in plain}) == 1
    lo, hi = plain[0].get_clim()
    assert (lo, hi) == (10.0 * 3 + 30 + 1, 10.0 * 5 + 90 + 40 + 1)  # min and max cell means
    assert len({im.get_clim() for im in diffs}) == 1
    d_lo, d_hi = diffs[0].get_clim()
    assert d_lo == -d_hi == -40.0  # HCOMC - FIFO = 40 everywhere, symmetric scale
    width, height = fig.get_size_inches()
    assert width <= 18.0
    assert height <= 12.0
    labels = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert "61" in labels  # FIFO, 3 s / 30 %: 30 + 30 + 1
    assert "mean over 3 seeds per cell" in fig._suptitle.get_text()


def test_heatmap_labels_cells_with_fewer_seeds():
    fig = heatmap_figure(_sweep_table(missing=True), "critical_distance")
    labels = [t.get_text() for ax in fig.axes for t in ax.texts]
    hcomc_cell = 10.0 * 3 + 30 + 40 + 0.5  # mean of seeds 0 and 1
    assert f"{hcomc_cell:.3g}\nn = 2" in labels
    assert "only k seeds give a value" in fig._suptitle.get_text()


def test_metrics_figure_marks_bars_with_missing_values_and_explains_them():
    runs = _sweep_table(missing=True).rename(columns={"mean_headway_main_2": "condition"})
    runs["condition"] = runs["condition"].map({3.0: "C3", 5.0: "C1"})
    runs = runs[runs["cav_penetration"] == 0.3]
    fig = metrics_figure(runs, metrics=["critical_distance"])
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert texts.count("n=2") == 1
    legend = fig.legends[0].get_title().get_text().replace("\n", " ")
    assert "mean over 3 seeds" in legend
    assert "VR did not merge" in legend  # the NaN critical distance is explained
    complete = metrics_figure(_sweep_table().assign(condition="C1"),
                              metrics=["critical_distance"])  # fmt: skip
    assert "n=" not in " ".join(t.get_text() for ax in complete.axes for t in ax.texts)


@pytest.fixture(scope="module")
def platoon_log():
    return simulate(load_config("platoon", duration=20.0))


def test_platoon_timespace_has_one_panel_and_no_merge_shading(platoon_log):
    fig = timespace_figure(platoon_log)
    panels = [ax for ax in fig.axes if ax.get_ylabel()]
    panels = [ax for ax in panels if "position" in ax.get_ylabel()]
    assert [ax.get_ylabel().split("\n")[0] for ax in panels] == ["lane 1"]
    assert not panels[0].patches  # no control zone / acceleration lane
    assert any(isinstance(c, LineCollection) for c in panels[0].collections)
    lo, _ = panels[0].get_ylim()
    assert lo > 2000.0  # zoomed to where the platoon drives, not the empty road


def test_trajectories_of_an_uncontrolled_run():
    log = simulate(load_config("C2", duration=40.0), seed=1)
    assert not log.meta.get("plans")
    fig = trajectories_figure(log)
    ax_path, ax_v, _ = fig.axes
    assert {ln.get_label() for ln in ax_path.lines} >= {"VR", "VMC"}
    assert not any("planned merge" in ln.get_label() for ln in ax_path.lines)
    assert any(ln.get_label() == "VR enters control zone" for ln in ax_v.lines)
    assert "no merge controller" in fig._suptitle.get_text()


def test_report_captions_are_numbered_once(tmp_path):
    from matplotlib.figure import Figure

    from hcomc.experiments.paper import PAPER_METRICS

    fig = Figure(figsize=(3, 2))
    fig.add_subplot().plot([0, 1])
    png = figure_png(fig)
    runs = pd.DataFrame(
        [{"condition": c, "configuration": conf, "seed": s, "mode": "longitudinal",
          **dict.fromkeys(PAPER_METRICS, 1.0 + s)}
         for c in ("C1", "C2", "C3", "C4", "C5")
         for conf in ("FIFO", "Game", "HCOMC", "HCOMC-PSO", "HCOMC-SA") for s in range(2)]
    )  # fmt: skip
    path = write_report(tmp_path, runs, figures={"Fig. 2 — contour": png, "Plain": png})
    html = path.read_text()
    assert "Figure 1. Fig." not in html
    assert "<figcaption>Fig. 2 — contour</figcaption>" in html
    assert "<figcaption>Figure 2. Plain</figcaption>" in html


def test_platoon_contour_is_one_uncontrolled_lane_without_merge_zones():
    from hcomc.viz.inputs import make_figure

    fig = make_figure("contour", ["platoon"], seed=0)
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in panels] == ["no controller · lane 1"]
    assert not panels[0].patches  # no control-zone / acceleration-lane band
    assert "of lane 1" in fig._suptitle.get_text()
