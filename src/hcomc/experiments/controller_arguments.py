"""Controllers named as arguments of :func:`hcomc.run` and :func:`hcomc.compare` (and of
``hcomc compare``'s options): a registered name, ``package.module:Class``,
``path/to/file.py:Class``, a configuration label such as ``HCOMC-R``, or a controller class,
checked into what the runner runs, with errors that name the argument (or option) as the
caller knows it."""

from __future__ import annotations

from collections.abc import Sequence

from hcomc.config import ConfigError
from hcomc.control.registry import canonical_name, class_spec
from hcomc.experiments.runner import configuration_label

__all__ = [
    "Controller",
    "baseline_label",
    "configuration_labels",
    "controller_name",
    "controller_spec",
]

Controller = str | type
"""A controller's name (or configuration label), or its class."""


def controller_spec(controller: object, argument: str) -> str:
    """A controller's name as the registry reads it: a name as given, a class as its spec
    (:func:`~hcomc.control.registry.class_spec`)."""
    if isinstance(controller, str):
        return controller
    if not isinstance(controller, type):
        raise ConfigError(
            f"argument '{argument}' = {controller!r}: not a name or a class; allowed: a "
            "controller name ('hcomc', 'package.module:Class', 'path/to/file.py:Class') or a "
            "controller class (every run builds its own controller from its config)"
        )
    try:
        return class_spec(controller)
    except ConfigError as exc:
        raise ConfigError(f"argument '{argument}' ({exc})") from None


def controller_name(controller: Controller) -> str:
    """The controller :func:`run` is given, as the config stores it; ConfigError naming it
    when it names none."""
    spec = controller_spec(controller, "controller")
    try:
        return canonical_name(spec)
    except ConfigError as exc:
        raise ConfigError(f"argument 'controller' ({exc})") from None


def configuration_labels(
    controllers: str | Sequence[Controller],
    *,
    key: str = "argument 'controllers'",
    least: int = 2,
) -> list[str]:
    """The configurations ``controllers`` stand for
    (:func:`~hcomc.experiments.runner.configuration_label`): ``least`` or more (two to
    compare), none empty or given twice; ConfigError naming the one that is not, as ``key``
    (the command line's ``option '--controllers'``)."""
    names = controllers.split(",") if isinstance(controllers, str) else list(controllers)
    shown = ", ".join(map(str, names))
    labels: list[str] = []
    for name in names:
        spec = controller_spec(name, "controllers").strip()
        if not spec:
            raise ConfigError(f"{key} = [{shown}]: an empty name")
        try:
            label = configuration_label(spec)
        except ConfigError as exc:
            raise ConfigError(f"{key} ({exc})") from None
        if label in labels:
            raise ConfigError(f"{key} = [{shown}]: '{spec}' is given twice")
        labels.append(label)
    if len(labels) < least:
        wanted = "two or more to compare" if least == 2 else f"{least} or more"
        raise ConfigError(f"{key} = [{shown}]: allowed: {wanted}, e.g. fifo,game,hcomc")
    return labels


def baseline_label(
    baseline: Controller, configurations: Sequence[str], *, key: str = "argument 'baseline'"
) -> str:
    """The configuration ``baseline`` stands for, one of those compared; ConfigError naming
    it as ``key`` (the command line's ``option '--baseline'``) otherwise."""
    spec = controller_spec(baseline, "baseline")
    try:
        label = configuration_label(spec)
    except ConfigError as exc:
        raise ConfigError(f"{key} ({exc})") from None
    if label not in configurations:
        raise ConfigError(
            f"{key} = '{spec}' is not among the controllers compared; allowed: "
            + ", ".join(configurations)
        )
    return label
