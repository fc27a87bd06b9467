"""A command's first run in a fresh environment says that it compiles hcomc's kernels, stage
by stage, instead of sitting silent for minutes (hcomc.cli._compile); it compiles only the
stages it needs, and a stage compiled for the current sources is silent; so does a learning
environment."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest
from rich.console import Console

import hcomc._jit
from hcomc._compiling import BUSY, Stage, machine
from hcomc._jit import stamp_tag
from hcomc.cli import _compile
from hcomc.cli._compile import ensure_compiled


def _console() -> tuple[Console, io.StringIO]:
    """A console as on a CI log: not a terminal."""
    text = io.StringIO()
    return Console(file=text, width=200), text


@pytest.fixture
def fake(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> dict:
    """The markers in tmp_path, the stages replaced by fakes that record what was printed
    before they ran."""
    console, text = _console()
    state: dict = {"console": console, "text": text, "runs": [], "printed": []}

    def stage(name: str):
        def run() -> None:
            state["runs"].append(name)
            state["printed"].append(text.getvalue())

        return run

    stages = {
        "step": Stage("step", stage("a"), 300.0),
        "optimisers": Stage("optimisers", stage("b"), 300.0),
    }
    monkeypatch.setattr(_compile, "cache_directory", lambda: tmp_path)
    monkeypatch.setattr(_compile, "STAGES", stages)
    monkeypatch.setattr(_compile, "IN_CHILD", False)  # the fakes record in this process
    monkeypatch.setattr(hcomc._jit, "remove_stale_caches", lambda: 0)
    state["stages"] = tuple(stages)
    state["marker"] = {key: tmp_path / f"hcomc-kernels-{stamp_tag()}-{key}.ok" for key in stages}
    return state


def test_the_first_call_says_so_before_compiling_and_writes_the_markers(fake: dict) -> None:
    ensure_compiled(fake["console"], fake["stages"])
    assert fake["runs"] == ["a", "b"]
    heading = fake["printed"][0]
    assert heading.startswith("compiling hcomc's kernels, once per environment")
    assert heading.count("\n") == 1  # one line, then the first stage's label
    assert "(about 10 min on one core)" in heading  # both stages: their cold seconds
    assert all(marker.exists() for marker in fake["marker"].values())
    lines = fake["text"].getvalue().splitlines()
    assert lines[1].startswith("  step … ")
    assert lines[1].endswith(" s")
    assert lines[2].startswith("  optimisers … ")
    assert lines[2].endswith(" s")
    assert "\x1b" not in fake["text"].getvalue()  # plain text off a terminal


def test_a_second_call_prints_nothing(fake: dict) -> None:
    ensure_compiled(fake["console"], fake["stages"])
    console, text = _console()
    ensure_compiled(console, fake["stages"])
    assert text.getvalue() == ""
    assert fake["runs"] == ["a", "b"]  # the stages ran once


def test_a_command_compiles_only_the_stages_it_needs(fake: dict) -> None:
    ensure_compiled(fake["console"], ("optimisers",))
    assert fake["runs"] == ["b"]
    assert "(about 5 min on one core)" in fake["printed"][0]  # one stage's cold seconds
    ensure_compiled(fake["console"], fake["stages"])
    assert fake["runs"] == ["b", "a"]  # the step now; the optimisers were compiled


def test_stale_markers_do_not_count_and_give_the_estimate(fake: dict) -> None:
    here = machine()
    stale = [
        fake["marker"]["step"].with_name("hcomc-kernels-0123456789abcdef-step.ok"),
        fake["marker"]["step"].with_name("hcomc-kernels-0123456789abcdef-optimisers.ok"),
    ]
    stale[0].write_text(json.dumps({"machine": here, "seconds": 125.0}))
    stale[1].write_text(json.dumps({"machine": here, "seconds": 60.0}))
    ensure_compiled(fake["console"], fake["stages"])
    assert fake["runs"] == ["a", "b"]
    assert "(at most 3 min on this machine; only what changed compiles)" in fake["printed"][0]
    assert all(marker.exists() for marker in fake["marker"].values())
    assert not any(path.exists() for path in stale)


def test_a_marker_of_another_numba_or_cpu_does_not_count(fake: dict) -> None:
    fake["marker"]["step"].write_text(json.dumps({"machine": "another", "seconds": 1.0}))
    ensure_compiled(fake["console"], ("step",))
    assert fake["runs"] == ["a"]
    assert json.loads(fake["marker"]["step"].read_text())["machine"] == machine()


def test_an_unwritable_cache_is_named_and_nothing_compiles(
    fake: dict, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(_compile, "cache_directory", lambda: tmp_path / "missing")
    ensure_compiled(fake["console"], fake["stages"])
    assert fake["runs"] == []
    assert "cannot be cached" in fake["text"].getvalue()


def test_no_cache_without_the_jit(monkeypatch: pytest.MonkeyPatch) -> None:
    """NUMBA_DISABLE_JIT: the kernels are plain Python functions, nothing to compile."""
    monkeypatch.setattr(hcomc._jit, "borrow", hcomc._jit.borrow.py_func)
    assert _compile.cache_directory() is None
    console, text = _console()
    ensure_compiled(console)
    assert text.getvalue() == ""


def test_the_real_replay_stage_leaves_its_marker_and_a_second_call_is_silent() -> None:
    """Not mocked: the replay's stage compiles (or loads) its kernel in a spawned process."""
    directory = _compile.cache_directory()
    assert directory == Path(hcomc._jit.borrow._cache.cache_path)  # numba's, for hcomc
    ensure_compiled(_console()[0], ("replay",))
    assert _compile.marker_path(directory, "replay").exists()
    console, text = _console()
    ensure_compiled(console, ("replay",))
    assert text.getvalue() == ""


def test_every_stage_has_a_label_and_the_scenario_stages_exist() -> None:
    assert set(_compile.SCENARIO) <= set(_compile.STAGES)
    assert all(stage.label and stage.cold_seconds > 0 for stage in _compile.STAGES.values())
    assert set(_compile.STAGES) == {
        "step",
        "prediction",
        "nsga2",
        "pso-sa",
        "batches",
        "replay",
        "corridor",
        "envs",
    }


def test_a_process_that_finds_another_compiling_waits_and_then_loads(fake: dict) -> None:
    """While another process holds the lock (here: this test, through its own open file, which
    flock treats as another holder), ``ensure_compiled`` says it waits; when the other one
    writes the markers and lets go, it compiles nothing."""
    import fcntl
    import threading

    lock = fake["marker"]["step"].parent / "hcomc-kernels.lock"
    held = lock.open("a")
    fcntl.flock(held, fcntl.LOCK_EX)
    done = threading.Event()
    waiter = threading.Thread(
        target=lambda: (ensure_compiled(fake["console"], fake["stages"]), done.set())
    )
    waiter.start()
    while "waiting" not in fake["text"].getvalue():
        assert waiter.is_alive()
        threading.Event().wait(0.01)
    assert not done.is_set()
    for marker in fake["marker"].values():
        marker.write_text(json.dumps({"machine": machine(), "seconds": 1.0}))
    fcntl.flock(held, fcntl.LOCK_UN)
    held.close()
    waiter.join(timeout=60)
    assert done.is_set()
    assert fake["runs"] == []  # the other process's kernels are loaded, not compiled again
    assert fake["text"].getvalue() == "waiting for another process compiling hcomc's kernels …\n"


def test_inside_a_compilation_nothing_waits_for_itself(
    fake: dict, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A stage's workload may construct what asks for its own stage (an environment does):
    inside a compilation, and in the processes it spawns, the call returns at once."""
    monkeypatch.setenv(BUSY, "1")
    ensure_compiled(fake["console"], fake["stages"])
    assert fake["runs"] == []
    assert fake["text"].getvalue() == ""


def test_an_environment_says_that_it_compiles_on_stderr(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A learning environment's first construction compiles the engine's stages it needs in
    its own process (its user's program), with the same lines on stderr; the next one is
    silent."""
    from hcomc.sim import stages as env_stages

    runs: list[str] = []
    fakes = {
        "step": Stage("simulation step", lambda: runs.append("step"), 65.0),
        "prediction": Stage("merge prediction", lambda: runs.append("prediction"), 6.0),
    }
    monkeypatch.setattr(env_stages, "cache_directory", lambda: tmp_path)
    monkeypatch.setattr(env_stages, "STAGES", fakes)
    monkeypatch.setattr(hcomc._jit, "remove_stale_caches", lambda: 0)
    from hcomc.envs.merge_env import MergeEnv

    MergeEnv("C1")
    err = capsys.readouterr().err.splitlines()
    assert runs == ["step"]  # the agent drives: no merge controller's kernels
    assert err[0].startswith("compiling hcomc's kernels, once per environment")
    assert "(about 65 s on one core)" in err[0]
    assert err[1].startswith("  simulation step … ")
    MergeEnv("C1")
    assert capsys.readouterr().err == ""
    assert runs == ["step"]
