"""A command's first run in a fresh environment says that it compiles hcomc's kernels, stage
by stage, instead of sitting silent for minutes (hcomc.cli._compile)."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest
from rich.console import Console

import hcomc._jit
from hcomc._jit import source_stamp
from hcomc.cli import _compile
from hcomc.cli._compile import ensure_compiled


def _console() -> tuple[Console, io.StringIO]:
    """A console as on a CI log: not a terminal."""
    text = io.StringIO()
    return Console(file=text, width=200), text


@pytest.fixture
def fake(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> dict:
    """The marker in tmp_path, the stages replaced by fakes that record what was printed
    before they ran."""
    console, text = _console()
    state: dict = {"console": console, "text": text, "runs": [], "printed": []}

    def stage(name: str):
        def run() -> None:
            state["runs"].append(name)
            state["printed"].append(text.getvalue())

        return run

    marker = tmp_path / f"hcomc-kernels-{source_stamp()[:16]}.ok"
    monkeypatch.setattr(_compile, "marker_path", lambda: marker)
    monkeypatch.setattr(_compile, "STAGES", (("step", stage("a")), ("optimisers", stage("b"))))
    monkeypatch.setattr(_compile, "IN_CHILD", False)  # the fakes record in this process
    state["marker"] = marker
    return state


def test_the_first_call_says_so_before_compiling_and_writes_the_marker(fake: dict) -> None:
    ensure_compiled(fake["console"])
    assert fake["runs"] == ["a", "b"]
    heading = fake["printed"][0]
    assert heading.startswith("compiling hcomc's kernels, once per environment")
    assert heading.count("\n") == 1  # one line, then the first stage's label
    assert "about " in heading
    assert " min" in heading
    assert fake["marker"].exists()
    lines = fake["text"].getvalue().splitlines()
    assert lines[1].startswith("  step … ")
    assert lines[1].endswith(" s")
    assert lines[2].startswith("  optimisers … ")
    assert lines[2].endswith(" s")
    assert "\x1b" not in fake["text"].getvalue()  # plain text off a terminal


def test_a_second_call_prints_nothing(fake: dict) -> None:
    ensure_compiled(fake["console"])
    console, text = _console()
    ensure_compiled(console)
    assert text.getvalue() == ""
    assert fake["runs"] == ["a", "b"]  # the stages ran once


def test_a_stale_marker_does_not_count_and_gives_the_estimate(fake: dict) -> None:
    machine = _compile._machine()
    stale = fake["marker"].with_name("hcomc-kernels-0123456789abcdef.ok")
    stale.write_text(json.dumps({"machine": machine, "seconds": 185.0}))
    ensure_compiled(fake["console"])
    assert fake["runs"] == ["a", "b"]
    assert "(about 3 min on this machine)" in fake["printed"][0]
    assert fake["marker"].exists()
    assert not stale.exists()


def test_a_marker_of_another_numba_or_cpu_does_not_count(fake: dict) -> None:
    fake["marker"].write_text(json.dumps({"machine": "another", "seconds": 1.0}))
    ensure_compiled(fake["console"])
    assert fake["runs"] == ["a", "b"]
    assert json.loads(fake["marker"].read_text())["machine"] == _compile._machine()


def test_an_unwritable_cache_is_named_and_nothing_compiles(
    fake: dict, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(_compile, "marker_path", lambda: tmp_path / "missing" / "m.ok")
    ensure_compiled(fake["console"])
    assert fake["runs"] == []
    assert "cannot be cached" in fake["text"].getvalue()


def test_no_cache_without_the_jit(monkeypatch: pytest.MonkeyPatch) -> None:
    """NUMBA_DISABLE_JIT: the kernels are plain Python functions, nothing to compile."""
    monkeypatch.setattr(hcomc._jit, "borrow", hcomc._jit.borrow.py_func)
    assert _compile.marker_path() is None
    console, text = _console()
    ensure_compiled(console)
    assert text.getvalue() == ""


def test_the_real_kernels_leave_the_marker_and_a_second_call_is_silent() -> None:
    """Not mocked: the stages compile (or, usually in a test session, load) every kernel, in
    a spawned process."""
    marker = _compile.marker_path()
    assert marker is not None
    assert marker.parent == Path(hcomc._jit.borrow._cache.cache_path)  # numba's, for hcomc
    ensure_compiled(_console()[0])
    assert marker.exists()
    console, text = _console()
    ensure_compiled(console)
    assert text.getvalue() == ""


def test_a_process_that_finds_another_compiling_waits_and_then_loads(fake: dict) -> None:
    """While another process holds the lock (here: this test, through its own open file, which
    flock treats as another holder), ``ensure_compiled`` says it waits; when the other one
    writes the marker and lets go, it compiles nothing."""
    import fcntl
    import threading

    lock = fake["marker"].parent / "hcomc-kernels.lock"
    held = lock.open("a")
    fcntl.flock(held, fcntl.LOCK_EX)
    done = threading.Event()
    waiter = threading.Thread(target=lambda: (ensure_compiled(fake["console"]), done.set()))
    waiter.start()
    while "waiting" not in fake["text"].getvalue():
        assert waiter.is_alive()
        threading.Event().wait(0.01)
    assert not done.is_set()
    fake["marker"].write_text(json.dumps({"machine": _compile._machine(), "seconds": 1.0}))
    fcntl.flock(held, fcntl.LOCK_UN)
    held.close()
    waiter.join(timeout=60)
    assert done.is_set()
    assert fake["runs"] == []  # the other process's kernels are loaded, not compiled again
    assert fake["text"].getvalue() == "waiting for another process compiling hcomc's kernels …\n"
