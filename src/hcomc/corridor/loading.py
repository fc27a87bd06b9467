"""Reading corridors: presets and TOML files, overrides, and one-line error messages.

A corridor file is a TOML file with a top-level ``[corridor]`` table (that table is what
tells it apart from a scenario config of :mod:`hcomc.config`). Like a scenario config it may
start from another corridor with ``base = "corridor"`` (a preset name or a path relative to
the file) and then sets only what differs; tables merge key by key, except the share tables
``classes`` and ``destinations``, which are replaced whole (their shares sum to 1), as are
lists.
Every error is a :class:`~hcomc.config.ConfigError` that names the key path
(``road.on_ramps[2].x``), the value and what is allowed.
"""

from __future__ import annotations

import os
import tomllib
from difflib import get_close_matches
from importlib.resources import files
from pathlib import Path
from typing import Any, get_args, get_origin

import tomli_w
from annotated_types import Ge, Gt, Le, Lt
from pydantic import BaseModel, ValidationError

from hcomc.config import ConfigError
from hcomc.corridor._base import RuleError
from hcomc.corridor.model import Corridor

__all__ = [
    "corridor_preset_names",
    "corridor_to_toml",
    "describe_corridor_error",
    "is_corridor_source",
    "load_corridor",
]

_PRESET_DIR = "configs/corridors"
_SHARE_TABLES = frozenset({"classes", "destinations"})


def corridor_preset_names() -> list[str]:
    """Names of the built-in corridors (``corridor``, ``paper``, ``paper-C1`` ... ``paper-C5``)."""
    root = files("hcomc").joinpath(_PRESET_DIR)
    return sorted(p.name.removesuffix(".toml") for p in root.iterdir() if p.name.endswith(".toml"))


def _preset(name: str) -> str | None:
    return {n.lower(): n for n in corridor_preset_names()}.get(name.lower())


def is_corridor_source(source: str | os.PathLike[str], _seen: tuple[Path, ...] = ()) -> bool:
    """Whether ``source`` names a corridor: a preset name, or a TOML file with a top-level
    ``[corridor]`` table or whose ``base`` is a corridor (anything else is left to the
    scenario configs)."""
    path = Path(source)
    if path.suffix != ".toml" and not path.exists():
        return _preset(str(source)) is not None
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8")) if path.is_file() else {}
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False
    if isinstance(data.get("corridor"), dict):
        return True
    base = data.get("base")
    if not isinstance(base, str) or path.resolve() in _seen:
        return False
    nearby = path.parent / base
    return is_corridor_source(nearby if nearby.is_file() else base, (*_seen, path.resolve()))


def _read(source: str | os.PathLike[str], seen: tuple[str, ...] = ()) -> tuple[dict[str, Any], str]:
    """The raw mapping of a preset or file with its ``base`` applied, and its origin."""
    path = Path(source)
    if path.suffix == ".toml" or path.exists():
        if not path.is_file():
            raise ConfigError(f"corridor file '{source}' does not exist")
        text, origin = path.read_text(encoding="utf-8"), str(path)
    else:
        name = _preset(str(source))
        if name is None:
            allowed = ", ".join(corridor_preset_names())
            raise ConfigError(f"unknown corridor '{source}'; allowed: {allowed} or a .toml file")
        text = files("hcomc").joinpath(f"{_PRESET_DIR}/{name}.toml").read_text(encoding="utf-8")
        origin = f"corridor preset {name}"
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{origin}: invalid TOML: {exc}") from None
    base = data.pop("base", None)
    if base is None:
        return data, origin
    if not isinstance(base, str):
        raise ConfigError(
            f"{origin}: key 'base' = {base!r}: allowed: a corridor preset name or a path"
        )
    identity = str(path.resolve())
    if identity in seen:
        raise ConfigError(f"{origin}: key 'base' = '{base}': circular ({' -> '.join(seen)})")
    nearby = path.parent / base
    try:
        base_data, _ = _read(
            nearby if path.is_file() and nearby.is_file() else base, (*seen, identity)
        )
    except ConfigError as exc:
        raise ConfigError(f"{origin}: key 'base' = '{base}': {exc}") from None
    return _merge(base_data, data), origin


def _merge(base: dict[str, Any], update: dict[str, Any]) -> dict[str, Any]:
    """``base`` with ``update`` applied: tables merge key by key, except share tables, which
    must sum to 1 and so are replaced whole; lists are replaced."""
    out = dict(base)
    for key, value in update.items():
        both = isinstance(value, dict) and isinstance(out.get(key), dict)
        both = both and key not in _SHARE_TABLES
        out[key] = _merge(out[key], value) if both else value
    return out


def load_corridor(
    source: str | os.PathLike[str], overrides: dict[str, Any] | None = None
) -> Corridor:
    """Load a corridor preset or file; ``overrides`` maps dotted keys (``corridor.duration``)
    to values, applied before validation. Raises :class:`~hcomc.config.ConfigError`."""
    data, origin = _read(source)
    for key, value in (overrides or {}).items():
        if value is None:
            continue
        nested: Any = value
        for part in reversed(key.split(".")):
            nested = {part: nested}
        data = _merge(data, nested)
    try:
        return Corridor.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(describe_corridor_error(exc, origin)) from None


def corridor_to_toml(corridor: Corridor) -> str:
    """The fully resolved corridor as TOML text that :func:`load_corridor` reads back."""
    return tomli_w.dumps(corridor.model_dump(mode="json", exclude_none=True))


# --------------------------------------------------------------------------- messages
def _path(loc: tuple[Any, ...]) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else f"{'.' if out else ''}{part}"
    return out


def _field_at(loc: tuple[Any, ...]) -> tuple[type[BaseModel] | None, Any]:
    """(model holding the last key of ``loc``, that key's FieldInfo or None)."""
    current: Any = Corridor
    model: type[BaseModel] | None = None
    info = None
    for part in loc:
        sub = _model_in(current)
        if sub is not None and isinstance(part, str):
            model = sub
            if part not in sub.model_fields:
                return model, None
            info = sub.model_fields[part]
            current = info.annotation
        else:  # a list item or a dict value
            args = get_args(current)
            current = args[-1] if get_origin(current) in (list, dict) and args else current
    return model, info


def _model_in(annotation: Any) -> type[BaseModel] | None:
    """The model class of ``X`` or ``X | None``, if any."""
    if get_origin(annotation) in (list, dict, tuple):
        return None
    for candidate in (annotation, *get_args(annotation)):
        if isinstance(candidate, type) and issubclass(candidate, BaseModel):
            return candidate
    return None


def _bounds(info: Any, name: str) -> str:
    """``"1 <= lanes <= 6"`` from a field's constraints ('' if it has none)."""
    lower = upper = ""
    for rule in getattr(info, "metadata", []):
        if isinstance(rule, Ge):
            lower = f"{rule.ge:g} <= "
        elif isinstance(rule, Gt):
            lower = f"{rule.gt:g} < "
        elif isinstance(rule, Le):
            upper = f" <= {rule.le:g}"
        elif isinstance(rule, Lt):
            upper = f" < {rule.lt:g}"
    return f"{lower}{name}{upper}" if lower or upper else ""


def describe_corridor_error(error: ValidationError, origin: str) -> str:
    """One line per problem: key path, offending value, what is allowed."""
    lines = []
    for item in error.errors():
        loc = tuple(item["loc"])
        problem = (item.get("ctx") or {}).get("error")
        if isinstance(problem, RuleError):
            lines.append(f"{origin}: {problem.message(_path(loc))}")
            continue
        key = _path(loc) or "(top level)"
        model, info = _field_at(loc)
        if item["type"] == "extra_forbidden":
            names = list(model.model_fields) if model is not None else []
            close = get_close_matches(str(loc[-1]), names, n=1, cutoff=0.6)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            lines.append(f"{origin}: unknown key '{key}'{hint}; allowed: {', '.join(names)}")
            continue
        described = f" ({info.description})" if info is not None and info.description else ""
        if item["type"] == "missing":
            lines.append(f"{origin}: key '{key}' is missing{described}")
            continue
        bounds = _bounds(info, str(loc[-1])) if item["type"] in _BOUND_TYPES else ""
        message = f"allowed: {bounds}" if bounds else item["msg"].removeprefix("Value error, ")
        lines.append(f"{origin}: key '{key}' = {item.get('input')!r}: {message}{described}")
    return "; ".join(lines)


_BOUND_TYPES = frozenset({"greater_than", "greater_than_equal", "less_than", "less_than_equal"})
