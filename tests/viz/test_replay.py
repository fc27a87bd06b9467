"""The browser replay: the packed arrays against the log, the plans and roles it shows,
``hcomc replay`` end to end (and its errors), the page's size, and the page itself in
headless Chromium read back through its JavaScript API."""

from __future__ import annotations

import base64
import itertools
import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.equations.collision import rectangle_corners
from hcomc.road import KEY_ROLES, Kind
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.viz.replay import ReplayPage, write_replay
from hcomc.viz.replay.browser import Chromium, find_chromium
from hcomc.viz.replay.decisions import moment_of_interest
from hcomc.viz.replay.pack import STEPS, columns_of

runner = CliRunner()
CONTROLLERS = ("fifo", "game", "hcomc")
TITLES = {
    "fifo": "FIFO · C2 · seed 1",
    "game": "Game · C2 · seed 1",
    "hcomc": "HCOMC (nsga2) · C2 · seed 1",
}
needs_chromium = pytest.mark.skipif(
    find_chromium() is None,
    reason="chromium is not installed (CI installs Debian's package in .ci/run)",
)


def simulate(out: Path, *args: str) -> Path:
    result = runner.invoke(app, ["simulate", *args, "--out", str(out)])
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """C2 seed 1 with FIFO, Game and HCOMC, 40 s (the merge ends near 25 s)."""
    base = tmp_path_factory.mktemp("runs")
    return {
        c: simulate(base / c, "C2", "--seed", "1", "--duration", "40", "--controller", c)
        for c in CONTROLLERS
    }


@pytest.fixture(scope="module")
def logs(runs: dict[str, Path]) -> dict[str, SimulationLog]:
    return {c: SimulationLog.load(path / "log.npz") for c, path in runs.items()}


@pytest.fixture(scope="module")
def page(runs: dict[str, Path], tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("page") / "replay.html"
    result = runner.invoke(app, ["replay", *(str(runs[c]) for c in CONTROLLERS), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert f"wrote {out}" in result.output.replace("\n", "")
    return out


def page_data(path: Path) -> dict[str, Any]:
    text = path.read_text(encoding="utf-8")
    block = re.search(
        r'<script type="application/json" id="replay-data">(.*?)</script>', text, re.S
    )
    assert block is not None
    return json.loads(block.group(1))


def decode(enc: dict[str, Any]) -> np.ndarray:
    data = np.frombuffer(base64.b64decode(enc["b64"]), dtype="<" + enc["dtype"])
    return data.reshape(enc["shape"])


def full(cells: Any, n: int) -> np.ndarray:
    """A log's (T, N) view as a plain array of its recorded rows."""
    return np.asarray(cells[:n])


# ----------------------------------------------------------------------------- the page


def test_page_is_self_contained(page: Path) -> None:
    text = page.read_text(encoding="utf-8")
    assert not re.search(r"\b(?:src|href)\s*=", text), "the page loads nothing"
    assert "http://" not in text
    assert "https://" not in text
    data = page_data(page)
    assert [r["title"] for r in data["runs"]] == [TITLES[c] for c in CONTROLLERS]


def test_packed_cells_are_the_log(page: Path, logs: dict[str, SimulationLog]) -> None:
    for run, c in zip(page_data(page)["runs"], CONTROLLERS, strict=True):
        log, arrays = logs[c], run["arrays"]
        n = log.n_recorded
        np.testing.assert_array_equal(decode(arrays["t"]), log.t[:n])
        column, first, last = (decode(arrays[k]) for k in ("column", "first", "last"))
        x = decode(arrays["x"])
        active = full(log.active, n)
        rows, ids = np.nonzero(active)
        cols = column[ids]
        # every cell of the log is in its vehicle's column, at its precision
        np.testing.assert_array_equal(x[rows, cols], full(log.x, n)[rows, ids])
        np.testing.assert_array_equal(
            decode(arrays["lane"])[rows, cols], full(log.lane, n)[rows, ids]
        )
        for name, nominal in STEPS.items():
            step, logged = arrays[name]["step"], full(getattr(log, name), n)[rows, ids]
            doublings, peak = math.log2(step / nominal), float(np.abs(logged).max())
            assert doublings == round(doublings) >= 0  # the nominal step, doubled k times
            assert peak / step <= 32767  # the smallest such step that fits int16
            assert step == nominal or peak / (step / 2) > 32767
            packed = decode(arrays[name])[rows, cols] * step
            np.testing.assert_allclose(packed, logged, atol=step / 2 + 1e-6)
        # a column holds one vehicle at a time, from its first row to its last
        assert (first[ids] <= rows).all()
        assert (rows <= last[ids]).all()
        assert np.isnan(x).sum() == x.size - rows.size
        assert run["columns"] == active.sum(axis=1).max()  # as few columns as possible
        np.testing.assert_array_equal(decode(arrays["kind"]), log.kind)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 40), st.integers(0, 15)), min_size=1, max_size=30))
def test_columns_partition_the_vehicles(intervals: list[tuple[int, int]]) -> None:
    n_rows, n = 60, len(intervals)
    active = np.zeros((n_rows, n), dtype=bool)
    for i, (start, length) in enumerate(intervals):
        active[start : start + length + 1, i] = True
    nan = np.where(active, 1.0, np.nan)
    log = SimulationLog(
        dt=0.1, t=np.arange(n_rows) * 0.1, x=nan, y=nan, v=nan, a=nan, heading=nan,
        lane=np.where(active, 1, -1), active=active, kind=np.zeros(n), length=np.full(n, 5.0),
        width=np.full(n, 2.0), n_recorded=n_rows,
    )  # fmt: skip
    layout = columns_of(log)
    assert layout.n_columns == active.sum(axis=1).max()
    for i, (start, length) in enumerate(intervals):
        assert (layout.first[i], layout.last[i]) == (start, min(start + length, n_rows - 1))
    for c in range(layout.n_columns):
        spans = sorted(
            (layout.first[i], layout.last[i]) for i in np.flatnonzero(layout.column == c)
        )
        assert all(a[1] < b[0] for a, b in itertools.pairwise(spans))


def live_record(log: SimulationLog, t: float) -> dict[str, Any] | None:
    """The plan record live at t: the last one made by t whose VR has not merged yet."""
    merges = log.events_of(EventKind.MERGE)
    live = None
    for record in log.meta.get("plans") or []:
        vr = record["group"]["VR"]
        merged = merges["t"][(merges["vehicle"] == vr) & (merges["t"] >= record["t0"])]
        if record["t0"] <= t and not (merged.size and merged.min() <= t):
            live = record
    return live


def test_plans_ghosts_and_roles(page: Path, logs: dict[str, SimulationLog]) -> None:
    run = page_data(page)["runs"][CONTROLLERS.index("hcomc")]
    log = logs["hcomc"]
    records = log.meta["plans"]
    assert len(run["plans"]) == len(records) >= 1
    times = log.t[: log.n_recorded]
    for plan, record in zip(run["plans"], records, strict=True):
        for key in ("mode", "sequence", "t0", "group", "eq19_branch", "decision_ms"):
            assert plan[key] == record[key]
        for ghost in plan["ghosts"]:
            coefficients = record[ghost["label"].lower()]
            tau = times[ghost["row"] : ghost["row"] + len(ghost["x"])] - record["t0"]
            assert tau[0] >= -1e-9
            assert tau[-1] <= record["horizon"] + 1e-9
            np.testing.assert_allclose(ghost["x"], np.polyval(coefficients[::-1], tau), atol=6e-4)
        # live from its decision until the same VR's next plan or its merge
        for t in (plan["start"], 0.5 * (plan["start"] + plan["end"])):
            assert live_record(log, t) == record
    first = log.meta["key_groups"][0]
    roles = run["roles"]
    entry = [k for k, t0 in enumerate(roles["t0"]) if t0 == first["t"] and roles["plan"][k] < 0]
    assert {KEY_ROLES[roles["role"][k]]: roles["vehicle"][k] for k in entry} == {
        r: first[r] for r in KEY_ROLES if first[r] >= 0
    }


def test_moment_of_interest_is_the_earliest_merge(logs: dict[str, SimulationLog]) -> None:
    middles = []
    for log in logs.values():
        vr = log.meta["key_groups"][0]["VR"]
        start = log.events_of(EventKind.LANE_CHANGE_START)
        merge = log.events_of(EventKind.MERGE)
        if (merge["vehicle"] == vr).any():
            t0 = start["t"][start["vehicle"] == vr].min()
            middles.append(0.5 * (t0 + merge["t"][merge["vehicle"] == vr].min()))
    assert middles
    assert moment_of_interest(list(logs.values())) == pytest.approx(min(middles))


def test_python_api(runs: dict[str, Path], tmp_path: Path) -> None:
    import hcomc.viz.replay.browser  # a submodule of the package does not hide the function

    page = hcomc.viz.replay([runs["fifo"], runs["hcomc"]], titles=["a", "b"])
    assert isinstance(page, ReplayPage)
    assert page._repr_html_().startswith('<iframe srcdoc="')
    again = write_replay(tmp_path / "r.html", [runs["fifo"], runs["hcomc"]], ["a", "b"])
    assert again.read_text(encoding="utf-8") == page.html.replace(
        "<title>hcomc replay</title>", "<title>a | b</title>"
    ).replace('"title":"hcomc replay"', '"title":"a | b"')
    assert callable(hcomc.viz.replay)


# ----------------------------------------------------------------------------- the command


def test_size_of_a_90_s_c1_run(tmp_path: Path) -> None:
    run = simulate(tmp_path / "c1", "C1", "--seed", "0", "--controller", "hcomc")
    out = tmp_path / "c1.html"
    result = runner.invoke(app, ["replay", str(run), "--out", str(out)])
    assert result.exit_code == 0, result.output
    log = SimulationLog.load(run / "log.npz")
    assert log.t[log.n_recorded - 1] == pytest.approx(90.0)
    assert out.stat().st_size <= 3_000_000


def test_the_paper_scenario_replays(tmp_path: Path) -> None:
    """The deterministic paper scenario of ``hcomc reproduce`` (uniform headways, no HDV
    estimation errors) replays like a seeded run: one panel, every logged time."""
    paper = ("--set", 'demand.pattern="uniform"', "--set", "hdv.estimation_errors=false")
    run = simulate(tmp_path / "paper", "C1", "--duration", "40", "--controller", "hcomc", *paper)
    out = tmp_path / "paper.html"
    result = runner.invoke(app, ["replay", str(run), "--out", str(out)])
    assert result.exit_code == 0, result.output
    log = SimulationLog.load(run / "log.npz")
    assert log.meta["config"]["demand"]["pattern"] == "uniform"
    (data,) = page_data(out)["runs"]
    np.testing.assert_array_equal(decode(data["arrays"]["t"]), log.t[: log.n_recorded])
    assert data["plans"], "HCOMC planned VR's merge"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["EMPTY"], "holds no log.npz or log.parquet"),
        (["MISSING"], "does not exist"),
        (["RUN", "--title", "a", "--title", "b"], "'--title' given 2 times for 1 runs"),
        (["RUN", "--at", "3"], "apply only with --screenshot"),
        (["BARE"], "road geometry is missing"),
    ],
)
def test_bad_input_is_a_one_line_error(
    runs: dict[str, Path], tmp_path: Path, args: list[str], message: str
) -> None:
    (tmp_path / "empty").mkdir()
    bare = runs["fifo"] / "log.npz"
    log = SimulationLog.load(bare)
    log.meta.pop("config")
    log.save(tmp_path / "bare.npz")
    where = {"EMPTY": tmp_path / "empty", "MISSING": tmp_path / "missing",
             "RUN": runs["fifo"], "BARE": tmp_path / "bare.npz"}  # fmt: skip
    argv = [str(where.get(a, a)) for a in args]
    result = runner.invoke(app, ["replay", *argv, "--out", str(tmp_path / "x.html")])
    assert result.exit_code == 2
    assert message in result.output
    assert "Traceback" not in result.output
    assert len(result.output.strip().splitlines()) == 1
    assert not (tmp_path / "x.html").exists()


def test_an_existing_page_is_kept_unless_forced(runs: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "kept.html"
    out.write_text("my notes")
    shot = tmp_path / "kept.png"
    for argv, option in ((["--out", str(out)], "--out"),
                         (["--out", str(tmp_path / "new.html"), "--screenshot", str(out)],
                          "--screenshot")):  # fmt: skip
        result = runner.invoke(app, ["replay", str(runs["fifo"]), *argv])
        assert result.exit_code == 2
        assert f"option '{option}' = '{out}': already exists" in result.output
        assert "--force" in result.output
    assert out.read_text() == "my notes"
    assert not shot.exists()
    assert not (tmp_path / "new.html").exists()
    result = runner.invoke(app, ["replay", str(runs["fifo"]), "--out", str(out), "--force"])
    assert result.exit_code == 0, result.output
    assert page_data(out)["runs"]


# ----------------------------------------------------------------------------- in Chromium


@pytest.fixture(scope="module")
def browser(page: Path) -> Any:
    with Chromium(1280, 900) as chrome:
        chrome.open(page.resolve().as_uri())
        yield chrome


def _row(log: SimulationLog, t: float) -> int:
    return int(np.argmin(np.abs(log.t[: log.n_recorded] - t)))


def _times(log: SimulationLog) -> list[float]:
    """Times to check: before the key group, during the plans, the merge, after it."""
    group_t = log.meta["key_groups"][0]["t"]
    t = log.t[: log.n_recorded]
    middle = moment_of_interest([log])
    picks = [group_t - 3.0, group_t + 0.45, middle, middle + 4.0]
    return [float(t[np.argmin(np.abs(t - p))]) for p in picks]


@needs_chromium
def test_page_loads_without_errors(browser: Chromium, logs: dict[str, SimulationLog]) -> None:
    assert browser.evaluate("window.hcomcReplay && hcomcReplay.ready") is True
    assert browser.console_errors == []
    assert browser.evaluate("hcomcReplay.runs()") == [TITLES[c] for c in CONTROLLERS]
    t = logs["fifo"].t
    assert browser.evaluate("hcomcReplay.range()") == [t[0], t[logs["fifo"].n_recorded - 1]]


def _crowded(log: SimulationLog, r: int, t: float) -> list[tuple[float, float]]:
    """(x, y) of what is drawn over or next to vehicles at row r: key vehicles (their labels)
    and the live plan's ghosts [m]."""
    out = []
    for group in [*log.meta["key_groups"], *(p["group"] for p in log.meta.get("plans") or [])]:
        for role in KEY_ROLES:
            k = group.get(role, -1)
            if k >= 0 and log.active[r, k]:
                out.append((float(log.x[r, k]), float(log.y[r, k])))
    record = live_record(log, t)
    if record is not None:
        for key, y in (("vv0", -3.75), ("vv1", 0.0), ("vv2", 3.75)):
            if record[key] is not None:
                out.append((float(np.polyval(record[key][::-1], t - record["t0"])), y))
    return out


@needs_chromium
def test_drawn_vehicles_are_where_the_log_says(
    browser: Chromium, logs: dict[str, SimulationLog]
) -> None:
    colours = {Kind.HDV: [0xD9, 0x5F, 0x02, 255], Kind.CAV: [0x1B, 0x9E, 0x77, 255]}
    checked = 0
    for t in _times(logs["hcomc"]):
        assert browser.evaluate(f"hcomcReplay.seek({t!r})") == t
        for k, c in enumerate(CONTROLLERS):
            log = logs[c]
            r = _row(log, t)
            ids = np.flatnonzero(np.asarray(log.active[r]))
            drawn = browser.evaluate(f"{ids.tolist()}.map((i) => hcomcReplay.vehicleAt(i, {k}))")
            crowd = _crowded(log, r, t)
            for i, d in zip(ids.tolist(), drawn, strict=True):
                x, y, h = (float(a[r, i]) for a in (log.x, log.y, log.heading))
                assert d["x"] == x  # float32, as logged
                assert abs(d["y"] - y) <= STEPS["y"] / 2 + 1e-6
                assert abs(d["heading"] - h) <= STEPS["heading"] / 2 + 1e-7
                expected = rectangle_corners(x, y, h, float(log.length[i]), float(log.width[i]))
                np.testing.assert_allclose(d["corners"], expected, atol=2e-3)
                alone = all(abs(cx - x) > 8.0 or abs(cy - y) > 5.0 for cx, cy in crowd)
                if alone:  # nothing drawn over it: its middle is its kind's colour
                    middle = x - 0.5 * float(log.length[i]) * math.cos(h)
                    pixel = browser.evaluate(
                        f"(() => {{ hcomcReplay.setView({{follow: false, cx: {middle!r}}}); "
                        f"const d = hcomcReplay.vehicleAt({i}, {k}); "
                        f"return hcomcReplay.pixel({k}, d.screen.x, d.screen.y); }})()"
                    )
                    assert pixel == colours[Kind(int(log.kind[i]))], f"{c}: vehicle {i}, t = {t}"
                    checked += 1
        browser.evaluate("hcomcReplay.home()")
    assert checked >= 10


@needs_chromium
def test_hover_panel_and_live_plan(browser: Chromium, logs: dict[str, SimulationLog]) -> None:
    for t in _times(logs["hcomc"]):
        browser.evaluate(f"hcomcReplay.seek({t!r})")
        for k, c in enumerate(CONTROLLERS):
            log = logs[c]
            r = _row(log, t)
            for i in np.flatnonzero(np.asarray(log.active[r]))[:8].tolist():
                text = browser.evaluate(f"hcomcReplay.hover({i}, {k})")
                assert text == browser.evaluate("hcomcReplay.panelText()")
                assert text.startswith(f"vehicle {i} · {Kind(int(log.kind[i])).name}")
                speed = float(re.search(r"speed (-?[\d.]+) m/s", text).group(1))
                assert abs(speed - float(log.v[r, i])) <= 0.005 + STEPS["v"]
                lane = int(re.search(r"lane (-?\d+)", text).group(1))
                assert lane == int(log.lane[r, i])
            shown = browser.evaluate(f"hcomcReplay.livePlan({k})")
            record = live_record(log, t)
            if record is None:
                assert shown is None, f"{c} at t = {t}"
            else:
                assert {key: shown[key] for key in record} == json.loads(
                    json.dumps(record).replace("NaN", "null")
                )
    browser.evaluate("hcomcReplay.hover(-1)")


def _key(browser: Chromium, key: str, code: str, text: str = "") -> None:
    for kind in ("keyDown", "keyUp"):
        params = {"type": kind, "key": key, "code": code}
        if text and kind == "keyDown":
            params["text"] = text
        browser.call("Input.dispatchKeyEvent", params)


@needs_chromium
def test_keyboard_shortcuts(browser: Chromium, logs: dict[str, SimulationLog]) -> None:
    t = logs["fifo"].t
    browser.evaluate(f"hcomcReplay.seek({float(t[100])!r})")
    _key(browser, "ArrowRight", "ArrowRight")
    assert browser.evaluate("hcomcReplay.time()") == t[101]
    _key(browser, "ArrowLeft", "ArrowLeft")
    _key(browser, "ArrowLeft", "ArrowLeft")
    assert browser.evaluate("hcomcReplay.time()") == t[99]
    _key(browser, "+", "Equal", "+")
    assert browser.evaluate("hcomcReplay.speed()") == 2
    _key(browser, "-", "Minus", "-")
    assert browser.evaluate("hcomcReplay.speed()") == 1
    _key(browser, "]", "BracketRight", "]")
    marks = [float(g["t"]) for log in logs.values() for g in log.meta["key_groups"]]
    hidden = [int(EventKind.INSERTION), int(EventKind.EXIT)]
    marks += [float(e["t"]) for log in logs.values() for e in log.events if e["kind"] not in hidden]
    assert browser.evaluate("hcomcReplay.time()") == min(m for m in marks if m > t[99] + 1e-6)
    _key(browser, " ", "Space", " ")
    assert browser.evaluate("hcomcReplay.playing()") is True
    _key(browser, " ", "Space", " ")
    assert browser.evaluate("hcomcReplay.playing()") is False
    assert browser.console_errors == []
