"""Merge controllers by name (configs name a registered key: ``control.controller``)."""

from __future__ import annotations

from collections.abc import Callable

from hcomc.config import ScenarioConfig
from hcomc.control.base import MergeController


def _hcomc(config: ScenarioConfig) -> MergeController:
    from hcomc.control.hcomc.controller import HCOMCController

    return HCOMCController(config)


def _fifo(config: ScenarioConfig) -> MergeController:
    from hcomc.control.fifo import FIFOController

    return FIFOController(config)


def _game(config: ScenarioConfig) -> MergeController:
    from hcomc.control.merge_game import GameController

    return GameController(config)


def _game_capped(config: ScenarioConfig) -> MergeController:
    from hcomc.control.merge_game import GameController

    return GameController(config, safety="capped")


CONTROLLERS: dict[str, Callable[[ScenarioConfig], MergeController]] = {
    "hcomc": _hcomc,
    "fifo": _fifo,
    "game": _game,
    "game-capped": _game_capped,
}


def make_controller(config: ScenarioConfig) -> MergeController | None:
    """The controller named by ``config.control.controller`` (None for 'none')."""
    name = config.control.controller
    if name == "none":
        return None
    if name not in CONTROLLERS:
        raise ValueError(f"unknown controller '{name}'; allowed: none, {', '.join(CONTROLLERS)}")
    return CONTROLLERS[name](config)
