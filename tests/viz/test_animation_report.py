"""Animation (GIF output, errors, atomic write) and the self-contained HTML report."""

from __future__ import annotations

import base64
import html
import io
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib import animation as mpl_animation
from matplotlib.figure import Figure
from PIL import Image

from hcomc.config import load_config
from hcomc.experiments.claims import claims
from hcomc.experiments.paper import PAPER_METRICS
from hcomc.sim.engine import simulate
from hcomc.sim.log import SimulationLog
from hcomc.viz.animation import animate
from hcomc.viz.page import figure_png
from hcomc.viz.report import write_report
from hcomc.viz.scene.frame import RoadScene

# ----------------------------------------------------------------------------- animation


@pytest.fixture(scope="module")
def c2_log() -> SimulationLog:
    """A short C2 run with the HCOMC controller (one merge plan around t = 11 s)."""
    log = simulate(load_config("C2", duration=40.0, control={"controller": "hcomc"}), seed=1)
    assert log.meta.get("plans"), "the fixture run should contain a merge plan"
    return log


@pytest.fixture(scope="module")
def gif(c2_log: SimulationLog, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("anim") / "run.gif"
    assert animate(c2_log, out, t_range=(5.0, 25.0)) == out
    return out


def _frames(path: Path) -> list[np.ndarray]:
    frames = []
    with Image.open(path) as im:
        for i in range(im.n_frames):
            im.seek(i)
            frames.append(np.asarray(im.convert("RGB"), dtype=np.float64))
    return frames


def test_gif_is_valid_and_animated(gif: Path) -> None:
    with Image.open(gif) as im:
        assert im.format == "GIF"
        # 20 s of simulated time, one frame every speedup / fps = 0.5 s.
        assert im.n_frames == 41
        assert im.size == (1200, 280)
    frames = _frames(gif)
    first, middle, last = frames[0], frames[len(frames) // 2], frames[-1]
    assert first.std() > 20.0, "frame looks blank"
    assert first.mean() < 250.0, "frame looks all white"
    for a, b in ((first, middle), (middle, last)):
        changed = np.any(a != b, axis=-1).mean()
        assert changed > 1e-3, "consecutive sampled frames should differ (vehicles move)"
    assert not list(gif.parent.glob(".*.tmp*")), "temporary files left behind"


def test_animator_draws_key_vehicles_and_ghosts(c2_log: SimulationLog) -> None:
    plan = c2_log.meta["plans"][0]
    animator = RoadScene(c2_log, (250.0, 1100.0))
    row_in = int(np.argmin(np.abs(c2_log.t - (plan["t0"] + 0.5))))  # before the first replan
    animator.update(row_in)
    assert len(animator.ghost_patches.get_paths()) == sum(
        plan[k] is not None for k in ("vv0", "vv1", "vv2")
    )
    assert len(animator.vehicles.get_paths()) > 5
    assert animator.labels["VR"].get_visible()
    assert animator.clock.get_text() == f"t = {c2_log.t[row_in]:.1f} s"
    # the ghosts are the first plan's cubics at that time (front bumper = max x of the patch)
    tau = c2_log.t[row_in] - plan["t0"]
    fronts = sorted(float(path.vertices[:, 0].max()) for path in animator.ghost_patches.get_paths())
    expected = sorted(
        float(np.polyval(plan[k][::-1], tau)) for k in ("vv0", "vv1", "vv2") if plan[k]
    )
    np.testing.assert_allclose(fronts, expected, atol=1e-6)


def test_mp4_without_ffmpeg_is_a_clear_error(
    c2_log: SimulationLog, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(mpl_animation.writers, "is_available", lambda name: False)
    with pytest.raises(ValueError, match=r"mp4 needs ffmpeg, which is not installed; use \.gif"):
        animate(c2_log, tmp_path / "run.mp4")
    assert not list(tmp_path.iterdir())


def test_other_extensions_are_rejected(c2_log: SimulationLog, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"'\.avi'.*\.gif, \.mp4"):
        animate(c2_log, tmp_path / "run.avi")
    with pytest.raises(ValueError, match="none"):
        animate(c2_log, tmp_path / "run")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"fps": 0}, "fps"),
        ({"speedup": -1.0}, "speedup"),
        ({"window": (900.0, 400.0)}, "window"),
        ({"t_range": (500.0, 600.0)}, "t_range"),
    ],
)
def test_bad_arguments(c2_log: SimulationLog, tmp_path: Path, kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        animate(c2_log, tmp_path / "run.gif", **kwargs)
    assert not list(tmp_path.iterdir())


def test_failing_render_leaves_no_partial_file(
    c2_log: SimulationLog, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def broken_finish(self: mpl_animation.PillowWriter) -> None:
        Path(self.outfile).write_bytes(b"GIF89a partial")  # half-written, then the disk fills
        raise OSError("No space left on device")

    monkeypatch.setattr(mpl_animation.PillowWriter, "finish", broken_finish)
    existing = tmp_path / "old.gif"
    existing.write_bytes(b"previous animation")
    with pytest.raises(OSError, match="No space left"):
        animate(c2_log, existing, t_range=(0.0, 2.0))
    with pytest.raises(OSError, match="No space left"):
        animate(c2_log, tmp_path / "new.gif", t_range=(0.0, 2.0))
    assert existing.read_bytes() == b"previous animation"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.gif"]


# ----------------------------------------------------------------------------- report

_CONFIGURATIONS = ("FIFO", "Game", "HCOMC", "HCOMC-PSO", "HCOMC-SA")
_HOSTILE = '<script>alert("x")</script> speed & flow'


@pytest.fixture(scope="module")
def runs() -> pd.DataFrame:
    """Synthetic results: 5 conditions x 5 configurations x 4 seeds."""
    rng = np.random.default_rng(7)
    records = []
    for cond in ("C1", "C2", "C3", "C4", "C5"):
        for conf in _CONFIGURATIONS:
            for seed in range(4):
                rec = {
                    "condition": cond,
                    "configuration": conf,
                    "seed": seed,
                    "mode": "lateral" if (conf == "HCOMC" and seed % 2) else "longitudinal",
                }
                rec.update({m: float(rng.uniform(1.0, 10.0)) for m in PAPER_METRICS})
                records.append(rec)
    return pd.DataFrame(records)


@pytest.fixture(scope="module")
def png() -> bytes:
    fig = Figure(figsize=(3, 2))
    ax = fig.add_subplot()
    ax.plot([0, 1, 2], [0, 1, 0], color="tab:blue")
    ax.set_title("test figure")
    return figure_png(fig)


@pytest.fixture(scope="module")
def report(runs: pd.DataFrame, png: bytes, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("report") / "nested"
    return write_report(out, runs, figures={_HOSTILE: png}, title="R&D <report>")


def test_figure_png(png: bytes) -> None:
    assert png.startswith(b"\x89PNG\r\n\x1a\n")
    with Image.open(io.BytesIO(png)) as im:
        assert im.size == (360, 240)  # 3 x 2 in at 120 dpi


def test_report_content(report: Path, runs: pd.DataFrame, png: bytes) -> None:
    assert report.name == "report.html"
    text = report.read_text(encoding="utf-8")
    for table_id in ("table-ii", "table-iii", "claims"):
        assert f'<table id="{table_id}">' in text
    assert text.count("<table") == 3
    assert "Table II" in text
    assert "Table III" in text
    # Three header rows; Table II has C1-C3 x 3 optimisers, Table III C1-C5 x 3 controllers.
    assert text.count("<tr>") == 3 + 9 + 15
    assert f"data:image/png;base64,{base64.b64encode(png).decode('ascii')}" in text
    # Claims coloured by their CI verdict, with the Holm verdict and k of n beside it.
    frame = claims(runs)
    for verdict in ("holds", "reversed", "undecided"):
        assert text.count(f'<tr class="{verdict}">') == int((frame["verdict"] == verdict).sum())
    assert text.count('<tr class="') == len(frame)
    assert "<th>Verdict (Holm)</th>" in text
    holds = int((frame["verdict"] == "holds").sum())  # no HCOMC+ runs: every claim the paper's
    assert set(frame["family"]) == {"paper"}
    assert html.escape(f"the paper's claims: {len(frame)} claims, {holds} hold") in text
    assert "The runs do not record merge success." in text  # no merged column
    # Escaped text, no markup injection.
    assert "<script" not in text.lower()
    assert "&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt; speed &amp; flow" in text
    assert "<title>R&amp;D &lt;report&gt;</title>" in text
    # Self-contained: no external resource or link of any kind.
    assert re.search(r"""\b(?:src|href)\s*=\s*["']?\s*(?:https?:)?//""", text, re.I) is None
    assert re.search(r"""url\(\s*["']?\s*(?:https?:)?//""", text, re.I) is None
    assert "http://" not in text
    assert "https://" not in text
    assert "<link" not in text.lower()
    assert "@import" not in text
    assert "docs/reproduction.md" in text


def test_report_takes_the_claims_already_computed(runs: pd.DataFrame, tmp_path: Path) -> None:
    """``reproduce`` passes its claims (with the paper scenario's "uniform" column): the page
    is the one the report computes itself, apart from the creation time in its header."""
    uniform = runs[runs["seed"] == 0]
    own = write_report(tmp_path / "own", runs).read_text(encoding="utf-8")
    given = write_report(tmp_path / "given", runs, claim_frame=claims(runs, uniform))
    created = re.compile(r"\d{4}-\d\d-\d\dT[\d:.]+(?:\+00:00|Z)?")
    assert created.sub("", given.read_text(encoding="utf-8")) == created.sub("", own)


def test_report_shows_merge_success_and_links_replays(runs: pd.DataFrame, tmp_path: Path) -> None:
    merged = runs.assign(merged=runs["seed"] != 3)  # the last of four seeds fails everywhere
    links = {"C2, seed 0: HCOMC": "replay/C2-seed0.html"}
    text = write_report(tmp_path, merged, replays=links).read_text(encoding="utf-8")
    table = text[text.index('<table id="merge-success">') :]
    table = table[: table.index("</table>")]
    assert table.count("<td>3/4</td>") == 5 * len(_CONFIGURATIONS)  # condition x configuration
    assert "<td>3/4</td>" in text[: text.index('<table id="merge-success">')]  # Tables II, III
    assert '<li><a href="replay/C2-seed0.html">C2, seed 0: HCOMC</a></li>' in text
    for bad in ("https://example.org/r.html", "//cdn/r.html", "/abs/r.html", "file:r.html"):
        with pytest.raises(ValueError, match="relative path"):
            write_report(tmp_path / "bad", runs, replays={"r": bad})


def test_report_rejects_bad_input(runs: pd.DataFrame, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="lsrv"):
        write_report(tmp_path, runs.drop(columns="lsrv"))
    with pytest.raises(ValueError, match="not PNG"):
        write_report(tmp_path, runs, figures={"bad": b"GIF89a"})
    assert not (tmp_path / "report.html").exists()


_CONSOLE_ERROR = re.compile(r"CONSOLE.*(error|uncaught)|uncaught.*CONSOLE", re.I)


@pytest.mark.skipif(
    shutil.which("chromium") is None,
    reason="chromium is not installed (CI installs Debian's package in .ci/run)",
)
def test_report_renders_in_headless_chromium(report: Path, tmp_path: Path) -> None:
    shot = tmp_path / "shot.png"
    cmd = [
        "chromium",
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        f"--user-data-dir={tmp_path / 'profile'}",
        "--enable-logging=stderr",
        "--v=0",
        "--window-size=1280,2000",
        f"--screenshot={shot}",
        report.resolve().as_uri(),
    ]
    proc = subprocess.run(
        cmd, capture_output=True, text=True, timeout=60, check=False, stdin=subprocess.DEVNULL
    )
    assert shot.is_file(), f"no screenshot (exit {proc.returncode}):\n{proc.stderr[-3000:]}"
    with Image.open(shot) as im:
        pixels = np.asarray(im.convert("RGB"), dtype=np.float64)
    assert pixels.shape[:2] == (2000, 1280)
    assert pixels.std() > 10.0, "screenshot looks blank"
    assert pixels.mean() < 250.0, "screenshot is (almost) all white"
    assert (pixels.min(axis=-1) < 200).mean() > 0.01, "too little is drawn"
    console_errors = [line for line in proc.stderr.splitlines() if _CONSOLE_ERROR.search(line)]
    assert not console_errors, "browser console errors:\n" + "\n".join(console_errors)
