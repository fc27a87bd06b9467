"""Compile hcomc's kernels before a command needs them, and say so (:func:`ensure_compiled`).

The kernels (:mod:`hcomc._jit`) compile on first use and are cached, once per environment and
after every change of the package's sources; a command's worker processes would otherwise sit
silent for minutes, each compiling the same kernels. :func:`ensure_compiled` compiles them
first with a line per stage, running tiny real workloads in one spawned process (compiling
leaves some 3 GB in a process, loading the cache 0.3 GB); the command then loads them.

**Is the cache complete?** The marker ``hcomc-kernels-<source stamp[:16]>.ok`` sits where numba
caches :func:`hcomc._jit.borrow`: ``NUMBA_CACHE_DIR``, else the in-tree ``__pycache__``, else
(a read-only tree) numba's user-wide cache; numba's locator checked that it can write there. It
holds what numba's cache index is keyed on besides the sources (numba version, Python, target
CPU: an upgrade or another machine sharing the cache recompiles) and the compilation's seconds
(the next estimate). A completed compilation deletes the in-tree cache files of earlier sources
(:func:`hcomc._jit.remove_stale_caches`). Deciding takes milliseconds once numba is imported,
as the command does anyway. With the JIT disabled there is nothing to compile; when the marker
cannot be written, every process compiles for itself, so one line says so.

**Several processes at once** (two commands, two test sessions): one compiles, holding an
exclusive lock on ``hcomc-kernels.lock`` beside the marker; the others say that they wait for
it, then find the marker and load the cache, instead of each compiling the same kernels.
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

ESTIMATE = "10-15 min: numba compiles on one core"
"""The estimate before the first compilation in a cache; later ones say the last
compilation's time."""


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
    worker, on all with ``--workers 1``; undisturbed runs; metrics), and the replay's drawing
    of lane changes (``reproduce``'s scene)."""
    import numba
    import numpy as np

    from hcomc.experiments.runner import ALL_CONFIGURATIONS, RunSpec, run_batch
    from hcomc.models.quintic import lateral_offset

    specs = [RunSpec("C2", label, 0, {"duration": 40.0}) for label in ALL_CONFIGURATIONS]
    run_batch(specs, threads=1)
    if int(numba.config.NUMBA_NUM_THREADS) > 1:  # type: ignore[attr-defined]
        run_batch(specs[:2], threads=2)  # the parallel kernel
    lateral_offset(np.linspace(0.0, 100.0, 3), 0.0, 100.0, 0.0, 3.75)


STAGES: tuple[tuple[str, Callable[[], None]], ...] = (
    ("simulation step", _tiny(("none", "nsga2"))),
    ("merge prediction of FIFO, Game and HCOMC", _tiny(("fifo", "nsga2"), ("game", "nsga2"))),
    ("NSGA-II", _tiny(("hcomc", "nsga2"))),
    ("PSO, SA", _tiny(("hcomc", "pso"), ("hcomc", "sa"))),
    ("ensemble runs, metrics and replay", _batches),
)
"""(label, workload): together they compile every kernel of ``hcomc simulate``, ``plan``,
``run`` and ``reproduce`` (measured: their processes compile nothing afterwards)."""

IN_CHILD = True
"""Run the stages in a spawned process (False: in this one, as the tests' fakes do)."""


def _stage(index: int) -> None:
    STAGES[index][1]()


@contextmanager
def _runner() -> Iterator[Callable[[int], None]]:
    """``run(i)`` runs stage i, in one spawned process for all stages (:data:`IN_CHILD`)."""
    if not IN_CHILD:
        yield _stage
        return
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        yield lambda index: pool.submit(_stage, index).result()


def marker_path() -> Path | None:
    """The marker of a complete cache for the current sources (None: no cache)."""
    from hcomc._jit import borrow, stamp_tag

    directory = getattr(getattr(borrow, "_cache", None), "cache_path", None)  # numba's
    return None if directory is None else Path(directory, f"hcomc-kernels-{stamp_tag()}.ok")


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


def _estimate(marker: Path, machine: str) -> str:
    """The last compilation's time in this cache (a marker of older sources), else
    :data:`ESTIMATE`."""
    found = [_read(p) for p in marker.parent.glob("hcomc-kernels-*.ok")]
    seconds = [m["seconds"] for m in found if m.get("machine") == machine and "seconds" in m]
    if seconds:
        return f"about {max(1, round(max(seconds) / 60))} min on this machine"
    return f"about {ESTIMATE}"


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


def ensure_compiled(console: Any) -> None:
    """Compile hcomc's kernels unless this environment's cache holds them for the current
    sources, with a line per stage on ``console`` (a rich Console); silent when it does."""
    marker = marker_path()
    if marker is None:
        return
    machine = _machine()
    if _read(marker).get("machine") == machine:
        return

    def say(text: str, end: str = "\n") -> None:
        console.print(text, end=end, markup=False, highlight=False, soft_wrap=True)
        console.file.flush()

    lock = marker.parent / "hcomc-kernels.lock"
    try:  # fail now, not after minutes; the lock, never the marker another process may write
        lock.touch()
    except OSError as exc:
        say(f"hcomc's kernels cannot be cached ({exc}): every process compiles them")
        return

    def waiting() -> None:
        say("waiting for another process compiling hcomc's kernels …")

    with _exclusive(lock, waiting):
        if _read(marker).get("machine") != machine:  # not compiled while this one waited
            _compile(marker, machine, say)


def _compile(marker: Path, machine: str, say: Callable[..., None]) -> None:
    """Run the stages, then write ``marker``."""
    say(
        "compiling hcomc's kernels, once per environment and after every change of its "
        f"sources ({_estimate(marker, machine)}) …"
    )
    start = time.perf_counter()
    with _runner() as run:
        for index, (label, _) in enumerate(STAGES):
            say(f"  {label} …", end="")
            began = time.perf_counter()
            run(index)
            say(f" {time.perf_counter() - began:.0f} s")
    seconds = time.perf_counter() - start
    for stale in marker.parent.glob("hcomc-kernels-*.ok"):
        stale.unlink(missing_ok=True)
    from hcomc._jit import remove_stale_caches

    remove_stale_caches()  # the in-tree cache files of earlier sources
    marker.write_text(json.dumps({"machine": machine, "seconds": seconds}), encoding="utf-8")
