"""Run manifests: provenance of a simulation run, and atomic file writes.

A manifest records everything needed to reproduce or audit a run: the seed (and the
``SeedSequence`` entropy derived from it), the resolved configuration, the package
version, the git revision of the source tree, and the interpreter, numpy and platform
versions. Manifests and sweep results are written atomically (temporary file in the
same directory, then :func:`os.replace`), so an interrupted write never leaves a
half-written file and never clobbers an existing good one.
"""

from __future__ import annotations

import datetime as _dt
import enum
import functools
import json
import os
import platform
import subprocess
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

import numpy as np

import hcomc

__all__ = [
    "atomic_paths",
    "build_manifest",
    "git_revision",
    "json_default",
    "write_json_atomic",
]

_GIT_TIMEOUT = 5.0  # [s]
_UNKNOWN = "unknown"


def _run_git(args: list[str], cwd: Path) -> str | None:
    """Run ``git <args>`` in *cwd*; return stripped stdout, or None on any failure."""
    env = dict(os.environ)
    # Read-only query: never take the index lock (other processes may be committing).
    env["GIT_OPTIONAL_LOCKS"] = "0"
    try:
        proc = subprocess.run(
            ["git", *args],
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=_GIT_TIMEOUT,
            check=False,
            env=env,
            stdin=subprocess.DEVNULL,
        )
    except (OSError, subprocess.SubprocessError, ValueError):
        return None
    if proc.returncode != 0:
        return None
    return proc.stdout.strip()


def git_revision(path: Path | None = None) -> str:
    """Git revision of the source tree containing *path*.

    Parameters
    ----------
    path : pathlib.Path or None
        A directory (or file) inside the working tree to query. Default: the directory
        of this module, i.e. the installed (editable) ``hcomc`` source tree.

    Returns
    -------
    str
        The full commit hash of ``HEAD``, with ``"-dirty"`` appended when
        ``git status --porcelain`` reports any change (untracked files included), or
        ``"unknown"`` when git is not installed, *path* is not inside a repository, the
        repository has no commit yet, or git takes longer than 5 [s]. Never raises.
        Computed once per process and directory (every run of a sweep shares it).
    """
    if path is None:
        return _revision_of(_SOURCE_DIR)
    try:
        cwd = Path(path)
        if cwd.is_file():
            cwd = cwd.parent
        if not cwd.is_dir():
            return _UNKNOWN
    except OSError:
        return _UNKNOWN
    return _revision_of(cwd)


_SOURCE_DIR = Path(__file__).resolve().parent  # the installed (editable) hcomc source tree


@functools.cache
def _revision_of(cwd: Path) -> str:
    head = _run_git(["rev-parse", "HEAD"], cwd)
    if not head:
        return _UNKNOWN
    status = _run_git(["status", "--porcelain"], cwd)
    if status:  # None (status failed) means "cannot tell": report the bare hash
        return f"{head}-dirty"
    return head


def json_default(obj: Any) -> Any:  # noqa: PLR0911 (one return per convertible type)
    """``default`` hook for :func:`json.dumps` that understands numpy and friends.

    Converts numpy scalars to Python scalars, numpy arrays to (nested) lists, paths to
    strings, datetimes to ISO 8601 strings, sets to sorted lists, enums to their value
    and pydantic models to their JSON-mode dump.

    Parameters
    ----------
    obj : object
        The object :mod:`json` could not serialise by itself.

    Returns
    -------
    object
        A JSON-serialisable equivalent.

    Raises
    ------
    TypeError
        If *obj* has no known JSON representation.
    """
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):  # numpy scalar: bool_, integer, floating, str_ ...
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, _dt.datetime | _dt.date):
        return obj.isoformat()
    if isinstance(obj, enum.Enum):
        return obj.value
    if isinstance(obj, set | frozenset):
        return sorted(obj, key=repr)
    dump = getattr(obj, "model_dump", None)  # pydantic v2 model
    if callable(dump):
        return dump(mode="json")
    raise TypeError(f"object of type {type(obj).__name__} is not JSON serialisable")


@functools.cache
def _new_file_mode() -> int:
    """Permission bits of a newly created file under the current umask."""
    umask = os.umask(0o022)
    os.umask(umask)
    return 0o666 & ~umask


def _target_mode(path: Path) -> int:
    """Keep an existing file's permissions; otherwise use the umask default."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        return _new_file_mode()


def _fsync_path(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextmanager
def atomic_paths(*paths: str | os.PathLike[str]) -> Iterator[list[Path]]:
    """Write one or more files atomically.

    Yields one temporary path per target, in the target's own directory (so the final
    :func:`os.replace` is atomic on POSIX and Windows). Write each file to its temporary
    path inside the ``with`` block. On normal exit the temporaries are flushed to disk
    and moved onto their targets **in the order given** (put the file that "commits" the
    set last). If the block raises (including ``KeyboardInterrupt``) every temporary is
    removed and the targets are left untouched.

    Parameters
    ----------
    *paths : str or os.PathLike
        Target file paths. Their directories must exist.

    Yields
    ------
    list of pathlib.Path
        Temporary paths, same order as *paths*. Each already exists (empty).

    Notes
    -----
    Each replacement is atomic, the set of several is not: a crash between two
    :func:`os.replace` calls can leave the first target new and the later ones old.
    Callers that need consistency across files should store a common token in each.
    """
    targets = [Path(p) for p in paths]
    temps: list[Path] = []
    try:
        for target in targets:
            fd, name = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
            os.close(fd)
            temps.append(Path(name))
        yield temps
        for target, tmp in zip(targets, temps, strict=True):
            _fsync_path(tmp)
            os.chmod(tmp, _target_mode(target))
        for target, tmp in zip(targets, temps, strict=True):
            os.replace(tmp, target)
    except BaseException:
        for tmp in temps:
            with suppress(OSError):
                tmp.unlink()
        raise


def write_json_atomic(path: str | os.PathLike[str], obj: Any) -> Path:
    """Write *obj* as pretty-printed JSON to *path*, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Target file. Its directory must exist. An existing file is replaced only once the
        new content is completely written.
    obj : object
        JSON-serialisable data; numpy scalars and arrays, paths, datetimes, enums and
        pydantic models are converted by :func:`json_default`.

    Returns
    -------
    pathlib.Path
        The target path.

    Raises
    ------
    TypeError
        If *obj* contains something that cannot be serialised (the target is untouched).
    """
    # Serialise first: a TypeError must not even create a temporary file.
    text = json.dumps(obj, indent=2, ensure_ascii=False, default=json_default) + "\n"
    target = Path(path)
    with atomic_paths(target) as (tmp,):
        tmp.write_text(text, encoding="utf-8")
    return target


def _jsonable(obj: Any) -> Any:
    """Deep copy of *obj* made of plain JSON types (dict, list, str, int, float, bool)."""
    return json.loads(json.dumps(obj, default=json_default))


_RESERVED = (
    "seed",
    "seed_entropy",
    "config",
    "hcomc_version",
    "git_revision",
    "python",
    "numpy",
    "platform",
    "created_utc",
)


@functools.cache
def _platform() -> str:
    """The machine's platform string (fixed for a process; a run's manifest asks each time)."""
    return platform.platform()


def build_manifest(
    *, seed: int, config: Mapping[str, Any] | Any, extra: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """Provenance record of one run.

    Parameters
    ----------
    seed : int
        The run's root seed (non-negative integer), as given to
        :class:`numpy.random.SeedSequence`.
    config : mapping or pydantic model
        The resolved configuration. It is copied into plain JSON types, so the manifest
        does not alias (or later see changes to) the caller's object.
    extra : mapping or None
        Additional JSON-serialisable entries (e.g. controller, condition, wall time).
        They may not reuse a standard key.

    Returns
    -------
    dict
        Keys ``seed``, ``seed_entropy``, ``config``, ``hcomc_version``, ``git_revision``,
        ``python``, ``numpy``, ``platform``, ``created_utc`` (ISO 8601, UTC, seconds),
        followed by the entries of *extra*. All values are JSON-serialisable.

    Raises
    ------
    TypeError
        If *seed* is not an integer or *config* / *extra* are not serialisable.
    ValueError
        If *seed* is negative or *extra* reuses a standard key.
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise TypeError(f"seed must be an int, got {type(seed).__name__}")
    seed = int(seed)
    if seed < 0:
        raise ValueError(f"seed must be >= 0, got {seed}")
    clash = sorted(set(extra or {}) & set(_RESERVED))
    if clash:
        raise ValueError(f"extra may not override standard manifest keys: {clash}")
    if not isinstance(config, Mapping) and callable(getattr(config, "model_dump", None)):
        plain = config.model_dump(mode="json")  # a new tree of plain JSON types already
    elif isinstance(config, Mapping):
        plain = _jsonable(dict(config))
    else:
        raise TypeError(f"config must be a mapping, got {type(config).__name__}")
    entropy = np.random.SeedSequence(seed).entropy
    manifest: dict[str, Any] = {
        "seed": seed,
        "seed_entropy": int(entropy) if isinstance(entropy, int) else None,
        "config": plain,
        "hcomc_version": hcomc.__version__,
        "git_revision": git_revision(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "platform": _platform(),
        "created_utc": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
    }
    manifest.update(_jsonable(dict(extra or {})))
    return manifest
