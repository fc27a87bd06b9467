"""Compile the kernels a command needs before it runs, and say so (:func:`ensure_compiled`).

The kernels (:mod:`hcomc._jit`) compile on first use and are cached, once per environment and
after an edit of the sources they depend on (:mod:`hcomc._stamp`: each kernel's module and
what it imports); a command's worker processes would otherwise sit silent for minutes, each
compiling the same kernels. :func:`ensure_compiled` compiles the stages a command needs first,
with a line per stage, running tiny real workloads in one spawned process (compiling leaves
some 3 GB in a process, loading the cache 0.3 GB); the command then loads them. A stage whose
kernels are all cached for the current sources loads them and costs seconds, so after an edit
of one kernel module only its kernels and those of the modules importing it compile.

**Is a stage compiled?** Its marker ``hcomc-kernels-<stamp tag>-<stage>.ok`` sits where numba
caches :func:`hcomc._jit.borrow`: ``NUMBA_CACHE_DIR``, else the in-tree ``__pycache__``, else
(a read-only tree) numba's user-wide cache. The stamp tag is the fingerprint of every kernel
module's stamp, so an edit of a module no kernel imports changes no marker. A marker holds
what numba's cache index is keyed on besides the sources (numba version, Python, target CPU:
an upgrade or another machine sharing the cache recompiles) and the stage's seconds (the next
estimate). A completed compilation deletes the in-tree cache files of earlier sources
(:func:`hcomc._jit.remove_stale_caches`). With the JIT disabled there is nothing to compile;
when the marker cannot be written, every process compiles for itself, so one line says so.

**Several processes at once** (two commands, two test sessions): one compiles, holding an
exclusive lock on ``hcomc-kernels.lock`` beside the markers; the others say that they wait for
it, then find the markers and load the cache, instead of each compiling the same kernels.
"""

from __future__ import annotations

import json
import multiprocessing
import sys
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

ESTIMATE_SECONDS = 600.0
"""The estimate of a cold compile of every stage before any compilation in this cache (numba
compiles on one core); later estimates are each stage's last time on this machine."""


def _tiny(*controls: tuple[str, str]) -> Callable[[], None]:
    """Short runs of Condition 2 (merge near t = 35 s), one per (controller, optimiser)."""

    def run() -> None:
        from hcomc.config import load_config
        from hcomc.sim.engine import Simulation

        for controller, optimizer in controls:
            control = {"controller": controller, "optimizer": optimizer}
            Simulation(load_config("C2", duration=40.0, control=control), 0).run()

    return run


def _batches() -> None:
    """Batches as ``run``, ``sweep`` and ``reproduce`` run them (ensemble on one thread in a
    worker, on all with ``--workers 1``; undisturbed runs; metrics)."""
    import numba

    from hcomc.experiments.runner import ALL_CONFIGURATIONS, RunSpec, run_batch

    specs = [RunSpec("C2", label, 0, {"duration": 40.0}) for label in ALL_CONFIGURATIONS]
    run_batch(specs, threads=1)
    if int(numba.config.NUMBA_NUM_THREADS) > 1:  # type: ignore[attr-defined]
        run_batch(specs[:2], threads=2)  # the parallel kernel


def _replay() -> None:
    """The replay's drawing of lane changes."""
    import numpy as np

    from hcomc.equations.lane_change import lateral_offset

    lateral_offset(np.linspace(0.0, 100.0, 3), 0.0, 100.0, 0.0, 3.75)


def _corridor() -> None:
    """A short run of the corridor preset, uncontrolled and with HCOMC at every ramp."""
    from hcomc.corridor.loading import load_corridor
    from hcomc.sim.corridor import simulate_corridor

    for controller in ("none", "hcomc"):
        corridor = load_corridor("corridor", {"control.controller": controller})
        simulate_corridor(corridor, seed=0, duration=30.0)


def _environments() -> None:
    """A few steps of the learning environments, single and vector (needs gymnasium)."""
    try:
        import gymnasium
    except ImportError:
        return
    import hcomc.envs  # noqa: F401  (registers the environments)

    env = gymnasium.make("hcomc/Merge-v0")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.close()
    from hcomc.envs.vector import MergeVectorEnv

    vector = MergeVectorEnv(2)
    vector.reset(seed=0)
    vector.step(vector.action_space.sample())
    vector.close()


STAGES: dict[str, tuple[str, Callable[[], None]]] = {
    "step": ("simulation step", _tiny(("none", "nsga2"))),
    "prediction": (
        "merge prediction of FIFO, Game and HCOMC",
        _tiny(("fifo", "nsga2"), ("game", "nsga2")),
    ),
    "nsga2": ("NSGA-II", _tiny(("hcomc", "nsga2"))),
    "pso-sa": ("PSO, SA", _tiny(("hcomc", "pso"), ("hcomc", "sa"))),
    "batches": ("ensemble runs and metrics", _batches),
    "replay": ("replay", _replay),
    "corridor": ("corridor engine", _corridor),
    "envs": ("learning environments", _environments),
}
"""key -> (label, workload): together they compile every kernel of the commands and the
environments (measured: their processes compile nothing afterwards)."""

SCENARIO = ("step", "prediction", "nsga2", "pso-sa", "batches")
"""The stages of a command that runs the paper's scenarios (``simulate``, ``plan``, ``run``,
``compare``, ``sweep``, ``reproduce``, ``faults``)."""

IN_CHILD = True
"""Run the stages in a spawned process (False: in this one, as the tests' fakes do)."""


def _stage(key: str) -> None:
    STAGES[key][1]()


@contextmanager
def _runner() -> Iterator[Callable[[str], None]]:
    """``run(key)`` runs a stage, in one spawned process for all stages (:data:`IN_CHILD`)."""
    if not IN_CHILD:
        yield _stage
        return
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        yield lambda key: pool.submit(_stage, key).result()


def cache_directory() -> Path | None:
    """Where numba caches hcomc's kernels (None: no cache, e.g. the JIT is disabled)."""
    from hcomc._jit import borrow

    directory = getattr(getattr(borrow, "_cache", None), "cache_path", None)  # numba's
    return None if directory is None else Path(directory)


def marker_path(directory: Path, stage: str) -> Path:
    """The marker of ``stage``'s kernels compiled for the current sources."""
    from hcomc._jit import stamp_tag

    return directory / f"hcomc-kernels-{stamp_tag()}-{stage}.ok"


def _machine() -> str:
    """What numba's cache index is keyed on besides the sources."""
    import numba
    from numba.core.registry import cpu_target

    magic = cpu_target.target_context.codegen().magic_tuple()
    return json.dumps([numba.__version__, sys.version_info[:2], *magic])


def _read(path: Path) -> dict[str, Any]:
    try:
        found = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return found if isinstance(found, dict) else {}


def _estimate(directory: Path, stages: list[str], machine: str) -> str:
    """The stages' last times on this machine in this cache, else :data:`ESTIMATE_SECONDS`
    shared by all stages; an upper bound when only some kernel modules changed."""
    last: dict[str, float] = {}
    for path in directory.glob("hcomc-kernels-*.ok"):
        found = _read(path)
        stage = path.stem.rpartition("-")[2]
        if found.get("machine") == machine and "seconds" in found:
            last[stage] = max(last.get(stage, 0.0), float(found["seconds"]))
    if not last:
        seconds = ESTIMATE_SECONDS * len(stages) / len(STAGES)
        return f"about {max(1, round(seconds / 60))} min on one core"
    seconds = sum(last.get(stage, ESTIMATE_SECONDS / len(STAGES)) for stage in stages)
    return f"at most {_duration(seconds)} on this machine; only what changed compiles"


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 90 else f"{round(seconds / 60)} min"


@contextmanager
def _exclusive(path: Path, on_wait: Callable[[], None]) -> Iterator[None]:
    """Hold an exclusive lock on ``path`` (created if missing), calling ``on_wait`` once if
    another process holds it; no lock where the OS has no ``fcntl``."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    with path.open("a") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            on_wait()
            fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            with suppress(OSError):
                fcntl.flock(handle, fcntl.LOCK_UN)


def ensure_compiled(console: Any, stages: tuple[str, ...] = SCENARIO) -> None:
    """Compile the kernels of ``stages`` (keys of :data:`STAGES`) unless this environment's
    cache holds them for the current sources, with a line per stage on ``console`` (a rich
    Console); silent when it does."""
    directory = cache_directory()
    if directory is None:
        return
    machine = _machine()

    def missing() -> list[str]:
        return [s for s in stages if _read(marker_path(directory, s)).get("machine") != machine]

    if not missing():
        return

    def say(text: str, end: str = "\n") -> None:
        console.print(text, end=end, markup=False, highlight=False, soft_wrap=True)
        console.file.flush()

    lock = directory / "hcomc-kernels.lock"
    try:  # fail now, not after minutes; the lock, never a marker another process may write
        lock.touch()
    except OSError as exc:
        say(f"hcomc's kernels cannot be cached ({exc}): every process compiles them")
        return

    def waiting() -> None:
        say("waiting for another process compiling hcomc's kernels …")

    with _exclusive(lock, waiting):
        todo = missing()  # not compiled while this one waited
        if todo:
            _compile(directory, todo, machine, say)


def _compile(directory: Path, stages: list[str], machine: str, say: Callable[..., None]) -> None:
    """Run ``stages``, writing each one's marker when it is done."""
    say(
        "compiling hcomc's kernels, once per environment and after an edit of their sources "
        f"({_estimate(directory, stages, machine)}) …"
    )
    with _runner() as run:
        for key in stages:
            say(f"  {STAGES[key][0]} …", end="")
            began = time.perf_counter()
            run(key)
            seconds = time.perf_counter() - began
            say(f" {seconds:.0f} s")
            for stale in directory.glob(f"hcomc-kernels-*-{key}.ok"):
                stale.unlink(missing_ok=True)
            record = {"machine": machine, "seconds": seconds}
            marker_path(directory, key).write_text(json.dumps(record), encoding="utf-8")
    from hcomc._jit import remove_stale_caches

    remove_stale_caches()  # the in-tree cache files of earlier sources
