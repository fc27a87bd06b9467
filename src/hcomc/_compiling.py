"""Compile kernels by stage before they are used, and say so (:func:`ensure`).

The kernels (:mod:`hcomc._jit`) compile on first use and are cached, once per environment and
after an edit of the sources they depend on (:mod:`hcomc._stamp`: each kernel's module and
what it imports). A process that used them straight away would sit silent for minutes; a
caller (a command, a learning environment) instead names the :class:`Stage` s it needs, and
:func:`ensure` runs each missing stage's tiny real workload first, with a line per stage. A
stage whose kernels are all cached for the current sources loads them and costs seconds, so
after an edit of one kernel module only its kernels and those of the modules importing it
compile. The stages themselves live with what they exercise (:mod:`hcomc.sim.stages` for the
engines, ``hcomc.cli._compile`` for the batches and the learning environments); this module
only knows how to run them.

**Is a stage compiled?** Its marker ``hcomc-kernels-<stamp tag>-<stage>.ok`` sits where numba
caches :func:`hcomc._jit.borrow`: ``NUMBA_CACHE_DIR``, else the in-tree ``__pycache__``, else
(a read-only tree) numba's user-wide cache. The stamp tag is the fingerprint of every kernel
module's stamp, so an edit of a module no kernel imports changes no marker. A marker holds
what numba's cache index is keyed on besides the sources (numba version, Python, target CPU:
an upgrade or another machine sharing the cache recompiles) and the stage's seconds (the next
estimate). A completed compilation deletes the in-tree cache files of earlier sources
(:func:`hcomc._jit.remove_stale_caches`).

**Several processes at once** (two commands, two test sessions): one compiles, holding an
exclusive lock on ``hcomc-kernels.lock`` beside the markers; the others say that they wait for
it, then find the markers and load the cache. While a process compiles, :data:`BUSY` is set in
its environment, so that a workload, or a process it spawns, never waits for itself.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any, NamedTuple

Say = Callable[..., None]
"""``say(text, end="\\n")``: writes a line (or a part of one) where the user sees it."""

BUSY = "HCOMC_COMPILING"
"""Environment variable set while this process (or its parent) runs stages."""


class Stage(NamedTuple):
    """A group of kernels compiled together by running ``workload`` once.

    ``workload`` is a module-level function (or a ``functools.partial`` of one), so that it can
    run in a spawned process; ``cold_seconds`` is its compile time from an empty cache on the
    development machine (``benchmarks/compile_profile.py``), the estimate before this machine
    has its own."""

    label: str
    workload: Callable[[], None]
    cold_seconds: float


def cache_directory() -> Path | None:
    """Where numba caches hcomc's kernels (None: no cache, e.g. the JIT is disabled)."""
    from hcomc._jit import borrow

    directory = getattr(getattr(borrow, "_cache", None), "cache_path", None)  # numba's
    return None if directory is None else Path(directory)


def marker_path(directory: Path, stage: str) -> Path:
    """The marker of ``stage``'s kernels compiled for the current sources."""
    from hcomc._jit import stamp_tag

    return directory / f"hcomc-kernels-{stamp_tag()}-{stage}.ok"


def machine() -> str:
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


def missing(directory: Path, keys: Sequence[str], here: str) -> list[str]:
    """The stages among ``keys`` without a marker for the current sources on this machine."""
    return [key for key in keys if _read(marker_path(directory, key)).get("machine") != here]


def _estimate(directory: Path, stages: Mapping[str, Stage], keys: list[str], here: str) -> str:
    """The stages' last times on this machine in this cache (an upper bound when only some
    kernel modules changed), else their cold times on the development machine."""
    last: dict[str, float] = {}
    for path in directory.glob("hcomc-kernels-*.ok"):
        found = _read(path)
        key = path.stem.rpartition("-")[2]
        if found.get("machine") == here and "seconds" in found:
            last[key] = max(last.get(key, 0.0), float(found["seconds"]))
    if not any(key in last for key in keys):
        seconds = sum(stages[key].cold_seconds for key in keys)
        return f"about {_duration(seconds)} on one core"
    seconds = sum(last.get(key, stages[key].cold_seconds) for key in keys)
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


@contextmanager
def _busy() -> Iterator[None]:
    """Mark this process (and those it spawns) as running stages."""
    os.environ[BUSY] = "1"
    try:
        yield
    finally:
        os.environ.pop(BUSY, None)


@contextmanager
def _runner(in_child: bool) -> Iterator[Callable[[Stage], None]]:
    """``run(stage)`` runs a stage's workload, in one spawned process for all stages (compiling
    leaves some 3 GB in a process, loading the cache 0.3 GB) or in this one."""
    if not in_child:
        yield lambda stage: stage.workload()
        return
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        yield lambda stage: pool.submit(stage.workload).result()


def ensure(
    directory: Path | None,
    stages: Mapping[str, Stage],
    keys: Sequence[str],
    say: Say,
    *,
    in_child: bool,
) -> None:
    """Compile the kernels of ``keys`` (of ``stages``) unless the cache in ``directory`` holds
    them for the current sources, with a line per stage through ``say``; silent when it does,
    when there is no cache (JIT disabled) and inside a compilation (:data:`BUSY`)."""
    if directory is None or os.environ.get(BUSY):
        return
    here = machine()
    if not missing(directory, keys, here):
        return
    lock = directory / "hcomc-kernels.lock"
    try:  # fail now, not after minutes; the lock, never a marker another process may write
        lock.touch()
    except OSError as exc:
        say(f"hcomc's kernels cannot be cached ({exc}): every process compiles them")
        return

    def waiting() -> None:
        say("waiting for another process compiling hcomc's kernels …")

    with _exclusive(lock, waiting), _busy():
        todo = missing(directory, keys, here)  # not compiled while this one waited
        if todo:
            _compile(directory, stages, todo, here, say, in_child)


def _compile(
    directory: Path, stages: Mapping[str, Stage], keys: list[str], here: str, say: Say,
    in_child: bool,
) -> None:  # fmt: skip
    """Run the stages ``keys``, writing each one's marker when it is done."""
    say(
        "compiling hcomc's kernels, once per environment and after an edit of their sources "
        f"({_estimate(directory, stages, keys, here)}) …"
    )
    with _runner(in_child) as run:
        for key in keys:
            say(f"  {stages[key].label} …", end="")
            began = time.perf_counter()
            run(stages[key])
            seconds = time.perf_counter() - began
            say(f" {seconds:.0f} s")
            for stale in directory.glob(f"hcomc-kernels-*-{key}.ok"):
                stale.unlink(missing_ok=True)
            record = {"machine": here, "seconds": seconds}
            marker_path(directory, key).write_text(json.dumps(record), encoding="utf-8")
    from hcomc._jit import remove_stale_caches

    remove_stale_caches()  # the in-tree cache files of earlier sources
