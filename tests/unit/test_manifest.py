"""Tests of hcomc.sim.manifest: atomic writes, run manifests, git revision, JSON."""

from __future__ import annotations

import datetime as dt
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import hcomc
from hcomc.sim import manifest as manifest_module
from hcomc.sim.log import EventKind
from hcomc.sim.manifest import (
    atomic_paths,
    build_manifest,
    git_revision,
    json_default,
    write_json_atomic,
)


def test_atomic_paths_cleans_up_on_keyboard_interrupt(tmp_path: Path) -> None:
    target = tmp_path / "x.bin"
    target.write_bytes(b"old")

    def interrupted_write() -> None:
        with atomic_paths(target) as (tmp,):
            tmp.write_bytes(b"new")
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        interrupted_write()
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["x.bin"]


def test_atomic_paths_keeps_file_mode(tmp_path: Path) -> None:
    target = tmp_path / "x.bin"
    target.write_bytes(b"old")
    target.chmod(0o640)
    with atomic_paths(target) as (tmp,):
        tmp.write_bytes(b"new")
    assert target.read_bytes() == b"new"
    assert target.stat().st_mode & 0o777 == 0o640


# ---------------------------------------------------------------------- manifest

MANIFEST_KEYS = {
    "seed",
    "seed_entropy",
    "config",
    "hcomc_version",
    "git_revision",
    "python",
    "numpy",
    "platform",
    "created_utc",
}


def test_build_manifest_keys_and_values() -> None:
    config = {"condition": "C1", "dt": np.float64(0.1), "lanes": (1, 2)}
    man = build_manifest(seed=12345, config=config, extra={"controller": "hcomc"})
    assert set(man) == MANIFEST_KEYS | {"controller"}
    assert man["seed"] == 12345
    assert man["seed_entropy"] == np.random.SeedSequence(12345).entropy
    assert man["config"] == {"condition": "C1", "dt": 0.1, "lanes": [1, 2]}
    assert man["hcomc_version"] == hcomc.__version__
    assert man["numpy"] == np.__version__
    assert isinstance(man["git_revision"], str)
    assert man["git_revision"]
    created = dt.datetime.fromisoformat(man["created_utc"])
    assert created.utcoffset() == dt.timedelta(0)
    assert man["controller"] == "hcomc"
    json.dumps(man, allow_nan=False)  # plain JSON throughout
    config["condition"] = "C2"
    assert man["config"]["condition"] == "C1"  # a copy, not an alias


def test_build_manifest_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="seed"):
        build_manifest(seed=-1, config={})
    with pytest.raises(TypeError, match="seed"):
        build_manifest(seed=1.5, config={})  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="override"):
        build_manifest(seed=1, config={}, extra={"seed": 2})


def test_git_revision_outside_repo_is_unknown(tmp_path: Path) -> None:
    outside = tmp_path / "not-a-repo"
    outside.mkdir()
    env_ceiling = os.environ.get("GIT_CEILING_DIRECTORIES")
    os.environ["GIT_CEILING_DIRECTORIES"] = str(tmp_path)  # git must not look further up
    try:
        assert git_revision(outside) == "unknown"
    finally:
        if env_ceiling is None:
            del os.environ["GIT_CEILING_DIRECTORIES"]
        else:
            os.environ["GIT_CEILING_DIRECTORIES"] = env_ceiling
    assert git_revision(tmp_path / "does-not-exist") == "unknown"


def test_git_revision_default_never_raises() -> None:
    rev = git_revision()
    assert re.fullmatch(r"unknown|[0-9a-f]{40}(-dirty)?", rev), rev


@pytest.mark.skipif(shutil.which("git") is None, reason="needs the git executable")
def test_git_revision_of_a_repository_is_its_head(tmp_path: Path) -> None:
    """Both outcomes on a repository made here: HEAD's hash, then "-dirty" with a change."""

    def git(*args: str) -> str:
        done = subprocess.run(
            ["git", "-c", "user.name=t", "-c", "user.email=t@example.org", *args],
            cwd=tmp_path, capture_output=True, text=True, check=True,
        )  # fmt: skip
        return done.stdout.strip()

    git("init", "-q")
    (tmp_path / "a.txt").write_text("a\n", encoding="utf-8")
    git("add", "a.txt")
    git("commit", "-q", "-m", "one")
    head = git("rev-parse", "HEAD")
    manifest_module._revision_of.cache_clear()
    try:
        assert git_revision(tmp_path) == head
        (tmp_path / "b.txt").write_text("b\n", encoding="utf-8")  # untracked: dirty
        manifest_module._revision_of.cache_clear()
        assert git_revision(tmp_path / "a.txt") == f"{head}-dirty"
    finally:
        manifest_module._revision_of.cache_clear()


def test_git_revision_without_git(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no git executable on PATH
    manifest_module._revision_of.cache_clear()  # computed once per process: forget it
    try:
        assert git_revision() == "unknown"
    finally:
        manifest_module._revision_of.cache_clear()


def test_git_revision_is_computed_once_per_process(monkeypatch: pytest.MonkeyPatch) -> None:
    first = git_revision()
    monkeypatch.setenv("PATH", "")  # git is gone, but the answer is remembered
    assert git_revision() == first


def test_write_json_atomic_handles_numpy(tmp_path: Path) -> None:
    obj = {
        "i": np.int32(3),
        "f": np.float32(0.5),
        "b": np.bool_(True),
        "arr": np.arange(3, dtype=np.int8),
        "mat": np.eye(2),
        "path": tmp_path / "x",
        "kind": EventKind.MERGE,
        "when": dt.datetime(2025, 1, 2, 3, 4, 5, tzinfo=dt.UTC),
    }
    target = write_json_atomic(tmp_path / "m.json", obj)
    text = target.read_text(encoding="utf-8")
    assert text.endswith("\n")
    assert "\n  " in text  # pretty-printed
    assert json.loads(text) == {
        "i": 3,
        "f": 0.5,
        "b": True,
        "arr": [0, 1, 2],
        "mat": [[1.0, 0.0], [0.0, 1.0]],
        "path": str(tmp_path / "x"),
        "kind": 3,
        "when": "2025-01-02T03:04:05+00:00",
    }
    assert [p.name for p in tmp_path.iterdir()] == ["m.json"]


def test_write_json_atomic_unserialisable_keeps_old_file(tmp_path: Path) -> None:
    target = tmp_path / "m.json"
    write_json_atomic(target, {"a": 1})
    with pytest.raises(TypeError, match="object"):
        write_json_atomic(target, {"a": object()})
    assert json.loads(target.read_text()) == {"a": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["m.json"]
    with pytest.raises(TypeError):
        json_default(object())
