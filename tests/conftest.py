"""Shared fixtures.

No test compiles kernels it does not use: each kernel compiles (or loads from numba's cache)
on its first call, so a unit test of one model compiles that model's kernels only. A command
run through the CLI compiles the stages it needs first (hcomc.cli._compile), with its lines on
the process's own stderr, never in the output a test checks."""

from __future__ import annotations

from typing import Any

import pytest

from hcomc.config import ScenarioConfig, load_config


@pytest.fixture(autouse=True)
def _empty_working_directory(tmp_path_factory: pytest.TempPathFactory, monkeypatch: Any) -> None:
    """Every test runs in an empty directory of its own, so no test reads or trips over what
    a command left in the checkout (``results/`` of ``hcomc reproduce``, ``sweeps/``, …)."""
    monkeypatch.chdir(tmp_path_factory.mktemp("cwd"))


@pytest.fixture
def platoon_config() -> Any:
    """Factory for a one-lane scripted-leader platoon config."""

    def make(
        profile: list[list[float]],
        *,
        kind: str = "hdv",
        followers: int = 1,
        duration: float = 30.0,
        initial_speed: float | None = None,
        hdv: dict[str, Any] | None = None,
    ) -> ScenarioConfig:
        return load_config(
            "platoon",
            duration=duration,
            hdv={"estimation_errors": False, **(hdv or {})},
            platoon={
                "followers": followers,
                "kind": kind,
                "initial_speed": profile[0][1] if initial_speed is None else initial_speed,
                "profile": profile,
            },
        )

    return make
