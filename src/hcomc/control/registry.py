"""Merge controllers by name: ``control.controller`` names a class, wherever it lives.

A name is one of

* a registered name: hcomc's own (``hcomc``, ``fifo``, ``game``, ``game-capped``) or one an
  installed package registers in the entry-point group ``hcomc.controllers``
  (``[project.entry-points."hcomc.controllers"] ctg = "my_pkg.ctg:CTG"``);
* ``package.module:Class``, a class of an importable module;
* ``path/to/file.py:Class``, a class of a Python file (relative to the working directory).

The class is built as ``Class(config, **options)``: ``config`` is the resolved
:class:`~hcomc.config.ScenarioConfig`, ``options`` the ``[control.options]`` table, checked
against the constructor's signature and type hints before anything runs. Every problem is a
:class:`~hcomc.config.ConfigError` naming the key, the value and what is allowed (the command
line reports it in one line and exits with 2).
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import sys
import typing
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

from pydantic import TypeAdapter, ValidationError

from hcomc.config import ConfigError, ScenarioConfig
from hcomc.interface import MergeController

ENTRY_POINT_GROUP = "hcomc.controllers"
"""Entry-point group through which installed packages register controller names."""

BUILTIN: dict[str, str] = {
    "fifo": "hcomc.control.fifo:FIFOController",
    "game": "hcomc.control.merge_game.controller:GameController",
    "hcomc": "hcomc.control.hierarchical.controller:HCOMCController",
    "game-capped": "hcomc.control.merge_game.controller:GameController",
}
"""hcomc's own controllers: name -> ``module:Class``."""

PRESET_OPTIONS: dict[str, dict[str, Any]] = {"game-capped": {"safety": "capped"}}
"""Constructor options a built-in name implies (the config's options come on top)."""


def registered() -> dict[str, str]:
    """Every registered name -> its ``module:Class``: hcomc's own, then those of installed
    packages (a package cannot take a built-in name)."""
    names = dict(BUILTIN)
    for point in entry_points(group=ENTRY_POINT_GROUP):
        names.setdefault(point.name, point.value)
    return names


def allowed_names() -> str:
    """What ``control.controller`` accepts, for error messages."""
    return f"none, {', '.join(registered())}, 'package.module:Class' or 'path/to/file.py:Class'"


def _error(spec: str, problem: str) -> ConfigError:
    return ConfigError(
        f"key 'control.controller' = '{spec}': {problem}; allowed: {allowed_names()}"
    )


_FILE_MODULE = "hcomc_user_"
"""How the module of a controller's Python file is named in ``sys.modules`` (then its stem
and a hash of its path)."""


def _is_file(target: str) -> bool:
    return target.endswith(".py") or "/" in target or "\\" in target


def _load_file(spec: str, target: str) -> Any:
    """The module of a Python file, loaded once per process under a name of its own."""
    path = Path(target).expanduser().resolve()
    if not path.is_file():
        raise _error(spec, f"file '{target}' does not exist")
    name = f"{_FILE_MODULE}{path.stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:8]}"
    if name in sys.modules:
        return sys.modules[name]
    found = importlib.util.spec_from_file_location(name, path)
    if found is None or found.loader is None:
        raise _error(spec, f"'{target}' is not a Python file")
    module = importlib.util.module_from_spec(found)
    sys.modules[name] = module  # dataclasses and pickling look the module up by name
    try:
        found.loader.exec_module(module)
    except Exception as exc:
        del sys.modules[name]
        raise _error(spec, f"'{target}' raised {type(exc).__name__}: {exc}") from None
    return module


def _load_module(spec: str, target: str) -> Any:
    try:
        return importlib.import_module(target)
    except ModuleNotFoundError as exc:
        raise _error(
            spec, f"no module '{exc.name}' (a file of your own: name it path/to/file.py:Class)"
        ) from None


def controller_class(spec: str) -> type:
    """The class a controller name (module doc) stands for; ConfigError if there is none.

    A built-in name is resolved without reading the installed packages' entry points (no
    package can take one, :func:`registered`): that reading takes milliseconds, and every run
    resolves its controller when it is built and again for its manifest."""
    target = BUILTIN[spec] if spec in BUILTIN else registered().get(spec, spec)
    module_name, colon, attr = target.rpartition(":")
    if not colon or not module_name:
        raise _error(spec, "not a registered name")
    load = _load_file if _is_file(module_name) else _load_module
    module = load(spec, module_name)
    cls = getattr(module, attr, None)
    if not inspect.isclass(cls):
        raise _error(spec, f"'{module_name}' has no class '{attr}'")
    if not callable(getattr(cls, "plan", None)):
        raise _error(spec, f"class '{attr}' has no method plan(view, group, rng)")
    return cls


def class_spec(cls: type) -> str:
    """The name a controller class goes by: ``package.module:Class``, or
    ``path/to/file.py:Class`` for a class loaded from a file; ConfigError for a class that
    cannot be loaded by name in another process (one defined in the running script, a
    notebook, or inside a function or class)."""
    module = cls.__module__
    if module in ("__main__", "__mp_main__") or cls.__qualname__ != cls.__name__:
        raise ConfigError(
            f"class {cls.__qualname__} of {module}: defined in the running script, a notebook "
            "or a function, so another process cannot load it by name; allowed: a class at "
            "the top of a module or a file (then 'path/to/file.py:Class')"
        )
    if module.startswith(_FILE_MODULE):  # loaded from a file by _load_file
        return f"{sys.modules[module].__file__}:{cls.__name__}"
    return f"{module}:{cls.__name__}"


def canonical_name(spec: str) -> str:
    """``spec`` as the config stores it: "none" or a registered name in lower case (names are
    case-insensitive), any other name unchanged; ConfigError if it names no controller."""
    lowered = spec.lower()
    if lowered == "none" or lowered in registered():
        if lowered != "none":
            controller_class(lowered)
        return lowered
    controller_class(spec)
    return spec


def _hints(cls: type) -> dict[str, Any]:
    """The constructor's resolved type hints ({} when they cannot be resolved)."""
    try:
        init = next(vars(k)["__init__"] for k in cls.__mro__ if "__init__" in vars(k))
        return typing.get_type_hints(init)
    except Exception:
        return {}


def checked_options(cls: type, options: dict[str, Any], spec: str) -> dict[str, Any]:
    """``options`` checked against ``cls(config, **options)``: every key a keyword of the
    constructor, every value of its type hint (converted as pydantic does, e.g. 2 -> 2.0)."""
    params = list(inspect.signature(cls).parameters.values())[1:]  # after config
    if any(p.kind is p.VAR_KEYWORD for p in params):
        return dict(options)
    keywords = {p.name: p for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}
    hints = _hints(cls)
    out: dict[str, Any] = {}
    for key, value in options.items():
        if key not in keywords:
            allowed = ", ".join(keywords) or "none (the constructor takes only the config)"
            raise ConfigError(
                f"key 'control.options.{key}' = {value!r}: not an option of controller "
                f"'{spec}'; allowed: {allowed}"
            )
        hint = hints.get(key, Any)
        try:
            adapter = TypeAdapter(hint)
        except Exception:  # a hint pydantic cannot check (an arbitrary class): taken as is
            out[key] = value
            continue
        try:
            out[key] = adapter.validate_python(value)
        except ValidationError as exc:
            rule = exc.errors()[0]["msg"]
            raise ConfigError(
                f"key 'control.options.{key}' = {value!r}: {rule}; allowed: {hint}"
            ) from None
    missing = [p.name for p in keywords.values() if p.default is p.empty and p.name not in options]
    if missing:
        raise ConfigError(
            f"key 'control.options' = {options!r}: controller '{spec}' needs "
            f"{', '.join(missing)}; allowed: a [control.options] table that sets them"
        )
    return out


def check_controller(config: ScenarioConfig) -> None:
    """Raise ConfigError if ``config``'s controller or its options cannot be built (the class
    is imported; nothing is constructed)."""
    spec = config.control.controller
    if spec != "none":
        checked_options(controller_class(spec), _options(config), spec)


def _options(config: ScenarioConfig) -> dict[str, Any]:
    spec = config.control.controller
    return {**PRESET_OPTIONS.get(spec, {}), **config.control.options}


def make_controller(config: ScenarioConfig) -> MergeController | None:
    """The controller ``config.control.controller`` names, built with its options (None for
    'none')."""
    spec = config.control.controller
    if spec == "none":
        if config.control.options:
            raise ConfigError(
                f"key 'control.options' = {config.control.options!r}: there is no controller "
                "to take them (control.controller = 'none'); allowed: an empty table"
            )
        return None
    cls = controller_class(spec)
    controller: MergeController = cls(config, **checked_options(cls, _options(config), spec))
    return controller


def controller_source(spec: str) -> dict[str, str]:
    """Where a controller's code comes from, for a run's manifest: its class, the file that
    defines it and that file's SHA-256 (a changed file is another controller)."""
    if spec == "none":
        return {}
    cls = controller_class(spec)
    path = inspect.getsourcefile(cls) or ""
    digest = hashlib.sha256(Path(path).read_bytes()).hexdigest() if path else ""
    return {"name": spec, "class": f"{cls.__module__}:{cls.__qualname__}", "file": path,
            "sha256": digest}  # fmt: skip
