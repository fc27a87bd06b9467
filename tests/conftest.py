"""Shared fixtures."""

from __future__ import annotations

from typing import Any

import pytest

from hcomc.config import ScenarioConfig, load_config


@pytest.fixture(autouse=True, scope="session")
def _kernels_compiled() -> None:
    """The kernels compiled once, first, as a command would (hcomc.cli._compile): the
    commands the tests run then print no compilation lines into the output they check."""
    from rich.console import Console

    from hcomc.cli._compile import ensure_compiled

    ensure_compiled(Console(stderr=True))


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
