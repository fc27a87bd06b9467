"""Reading, overriding and writing scenario configs: presets, TOML files, ``--set`` keys.

Every error names the key, the value and what is allowed (:class:`ConfigError`).
"""

from __future__ import annotations

import os
import tomllib
from difflib import get_close_matches
from importlib.resources import files
from pathlib import Path
from typing import Any, get_args, get_origin

import tomli_w
from pydantic import (
    BaseModel,
    ValidationError,
)
from pydantic.fields import FieldInfo

from hcomc.config.schema import (
    ConfigError,
    ScenarioConfig,
)

__all__ = [
    "config_to_toml",
    "describe_error",
    "leaf_paths",
    "load_config",
    "nest_overrides",
    "preset_names",
    "suggest",
    "validate_config",
]

_PRESET_DIR = "configs/conditions"
_UNTRACKED = frozenset({"name", "description", "seed"})  # not worth a description note


def preset_names() -> list[str]:
    """Names of the built-in presets (``C1`` … ``C5``, ``platoon``)."""
    root = files("hcomc").joinpath(_PRESET_DIR)
    return sorted(p.name.removesuffix(".toml") for p in root.iterdir() if p.name.endswith(".toml"))


# --------------------------------------------------------------------------- key index
def _sub_model(annotation: Any) -> type[BaseModel] | None:
    """The pydantic model class of a field annotation (``X`` or ``X | None``), if any; a
    list of tables (``tuple[X, ...]``, TOML's ``[[x]]``) is a key of its own."""
    if get_origin(annotation) in (tuple, list):
        return None
    for candidate in (annotation, *get_args(annotation)):
        if isinstance(candidate, type) and issubclass(candidate, BaseModel):
            return candidate
    return None


def leaf_paths(model: type[BaseModel] | None = None) -> dict[str, FieldInfo]:
    """Every settable dotted key of ``model`` (default :class:`ScenarioConfig`) -> its field."""
    model = model or ScenarioConfig
    paths: dict[str, FieldInfo] = {}
    for name, info in model.model_fields.items():
        sub = _sub_model(info.annotation)
        if sub is None:
            paths[name] = info
        else:
            paths.update({f"{name}.{k}": v for k, v in leaf_paths(sub).items()})
    return paths


def suggest(key: str, model: type[BaseModel] | None = None) -> str:
    """``"; did you mean 'x.y'?"`` for an unknown dotted ``key``, or ``""`` if nothing is close.

    A key in the wrong table (``demand.time_headway``) is pointed to its homes; a misspelt
    table or key to the closest spelling (``demnd`` -> ``demand``, ``cav.coolnes`` ->
    ``cav.coolness``, ``controler`` -> ``control.controller``).
    """
    model = model or ScenarioConfig
    paths = list(leaf_paths(model))
    *table, leaf = key.split(".")
    prefix = ".".join(table)
    homes = [p for p in paths if p.rsplit(".", 1)[-1] == leaf and p != key]
    if not homes:
        homes = _closest(prefix, leaf, model, paths)
    if not homes:
        return ""
    return "; did you mean " + " or ".join(f"'{h}'" for h in homes) + "?"


def _closest(prefix: str, leaf: str, model: type[BaseModel], paths: list[str]) -> list[str]:
    """The closest spelling of ``prefix.leaf`` among tables and keys (at most one)."""
    tables = {p.rsplit(".", 1)[0] for p in paths if "." in p}
    if not prefix:  # a top-level key, a table name, or a flat key with one home
        leaves: dict[str, list[str]] = {}
        for p in paths:
            leaves.setdefault(p.rsplit(".", 1)[-1], []).append(p)
        names = {n: n for n in model.model_fields}
        names.update({n: ps[0] for n, ps in leaves.items() if len(ps) == 1 and n not in names})
        match = get_close_matches(leaf, list(names), n=1, cutoff=0.6)
        return [names[match[0]]] if match else []
    if prefix not in tables:  # a misspelt table: fix it, keep the key if it lives there
        match = get_close_matches(prefix, sorted(tables), n=1, cutoff=0.6)
        if not match:
            return []
        fixed = f"{match[0]}.{leaf}"
        return [fixed] if fixed in paths else [match[0]]
    siblings = {p.rsplit(".", 1)[-1]: p for p in paths if p.rsplit(".", 1)[0] == prefix}
    match = get_close_matches(leaf, list(siblings), n=1, cutoff=0.6)
    return [siblings[match[0]]] if match else []


# --------------------------------------------------------------------------- reading
def _read_toml(source: str | os.PathLike[str]) -> tuple[dict[str, Any], str]:
    """Return the raw TOML mapping of a preset name or file path, and its origin."""
    path = Path(source)
    if path.suffix == ".toml" or path.exists():
        if not path.is_file():
            raise ConfigError(f"config file '{source}' does not exist")
        text, origin = path.read_text(encoding="utf-8"), str(path)
    else:
        names = preset_names()
        match = {n.lower(): n for n in names}.get(str(source).lower())
        if match is None:
            raise ConfigError(
                f"unknown preset '{source}'; allowed: {', '.join(names)} or a path to a .toml file"
            )
        text = files("hcomc").joinpath(f"{_PRESET_DIR}/{match}.toml").read_text(encoding="utf-8")
        origin = f"preset {match}"
    try:
        return tomllib.loads(text), origin
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{origin}: invalid TOML: {exc}") from None


def _resolve_base(
    source: str | os.PathLike[str], seen: tuple[str, ...] = ()
) -> tuple[dict[str, Any], dict[str, Any] | None, str]:
    """``(data, base data or None, origin)`` of a config, with its ``base = ...`` applied.

    A file's ``base`` (a preset name, or a TOML path relative to the file) supplies every
    value the file leaves out; the file's name defaults to its stem, not the base's.
    """
    data, origin = _read_toml(source)
    if "base" not in data:
        return data, None, origin
    base = data.pop("base")
    if not isinstance(base, str):
        raise ConfigError(
            f"{origin}: key 'base' = {base!r}: must be a preset name "
            f"({', '.join(preset_names())}) or a path to a .toml file"
        )
    identity = str(Path(source).resolve())  # one spelling per file, so cycles are seen
    if identity in seen:
        raise ConfigError(f"{origin}: key 'base' = '{base}': circular ({' -> '.join(seen)})")
    nearby = Path(source).parent / base
    target = nearby if Path(origin).is_file() and nearby.is_file() else base
    try:
        base_data, _, _ = _resolve_base(target, (*seen, identity))
    except ConfigError as exc:
        raise ConfigError(f"{origin}: key 'base' = '{base}': {exc}") from None
    data.setdefault("name", Path(source).stem)
    return merge_tables(base_data, data), base_data, origin


def describe_error(
    error: ValidationError,
    origin: str,
    model: type[BaseModel] | None = None,
) -> str:
    """One line per problem: dotted key, offending value, what is allowed (and a suggestion)."""
    lines = []
    for item in error.errors():
        key = ".".join(str(p) for p in item["loc"]) or "(top level)"
        if item["type"] == "extra_forbidden":
            hint = suggest(key, model) or "; not allowed"
            lines.append(f"{origin}: unknown key '{key}' (value {item['input']!r}){hint}")
        else:
            value = item.get("input")
            shown = "(missing)" if item["type"] == "missing" else repr(value)
            msg = item["msg"].removeprefix("Value error, ")
            lines.append(f"{origin}: key '{key}' = {shown}: {msg}")
    return "; ".join(lines)


def validate_config(data: dict[str, Any], origin: str = "config") -> ScenarioConfig:
    """Validate a raw mapping into a :class:`ScenarioConfig`, raising :class:`ConfigError`."""
    try:
        return ScenarioConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(describe_error(exc, origin)) from None


# --------------------------------------------------------------------------- overrides
def nest_overrides(overrides: dict[str, Any]) -> dict[str, Any]:
    """Overrides as one nested mapping; ``None`` values are dropped (= keep the config's).

    Keys may be top-level (``duration``, ``demand={...}``), dotted
    (``"demand.cav_penetration"``) or a flat leaf name with one home
    (``cav_penetration`` -> ``demand.cav_penetration``). A flat name with several homes
    (``time_headway``: ``hdv`` and ``cav``) is an error naming them.
    """
    top = ScenarioConfig.model_fields
    paths = leaf_paths()
    nested: dict[str, Any] = {}
    for key, value in overrides.items():
        if value is None:
            continue
        if "." in key and key not in paths and not _in_table(key, paths):
            raise ConfigError(
                f"unknown override '{key}' = {value!r}{suggest(key) or '; not a config key'}"
            )
        if "." in key or key in top:
            path = key.split(".")
        else:
            homes = [p for p in paths if p.rsplit(".", 1)[-1] == key]
            if len(homes) > 1:
                raise ConfigError(
                    f"override '{key}' = {value!r} is ambiguous; allowed: "
                    + ", ".join(f"'{h}'" for h in homes)
                )
            if not homes:
                raise ConfigError(
                    f"unknown override '{key}' = {value!r}{suggest(key) or '; not a config key'}"
                )
            path = homes[0].split(".")
        leaf: Any = value
        for part in reversed(path[1:]):
            leaf = {part: leaf}
        nested = merge_tables(nested, {path[0]: leaf})
    return nested


def _in_table(key: str, paths: dict[str, FieldInfo]) -> bool:
    """Whether dotted ``key`` names an entry of a free-form table such as ``control.options``
    (a leaf whose value is a mapping: its entries are the user's, not the schema's)."""
    return any(
        key.startswith(f"{path}.") and get_origin(info.annotation) is dict
        for path, info in paths.items()
    )


def _flat(data: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, dict):
            out.update(_flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def _note_changes(config: ScenarioConfig, reference: ScenarioConfig) -> ScenarioConfig:
    """``config`` whose description lists the values that differ from ``reference``'s.

    A preset's description states its values ("CAV penetration 0.9"); after an override it
    must not keep claiming them.
    """
    new, old = _flat(config.model_dump(mode="json")), _flat(reference.model_dump(mode="json"))
    changed = [
        f"{k} {old.get(k)!r} -> {v!r}"
        for k, v in new.items()
        if k not in _UNTRACKED and old.get(k) != v
    ]
    if not changed or config.description != reference.description:
        return config
    note = f"changed from {reference.name}: {', '.join(changed)}"
    text = f"{config.description}; {note}" if config.description else note
    return config.model_copy(update={"description": text})


def load_config(source: str | os.PathLike[str], **overrides: Any) -> ScenarioConfig:
    """Load a preset name (``C1``, ``platoon`` …) or a TOML file into a validated config.

    A file may start from another config with ``base = "C2"`` (or a path); it then sets only
    what differs. ``overrides`` (``duration=600``, ``cav_penetration=0.5``,
    ``**{"demand.cav_penetration": 0.5}`` or ``demand={"cav_penetration": 0.5}``; nested
    tables merge key by key) are applied before validation, so they are checked like file
    values. When the result differs from the base or preset, its description says how.
    Raises :class:`ConfigError` with a one-line message.
    """
    data, base_data, origin = _resolve_base(source)
    update = nest_overrides(overrides)
    config = validate_config(merge_tables(data, update), origin)
    reference_data = base_data if base_data is not None else data
    if reference_data is data and not update:
        return config
    try:
        reference = validate_config(reference_data, origin)
    except ConfigError:  # an invalid base that the overrides repair: nothing to compare to
        return config
    return _note_changes(config, reference)


def merge_tables(base: dict[str, Any], update: dict[str, Any]) -> dict[str, Any]:
    """``base`` with ``update`` applied: nested tables merged key by key, any other value of
    ``update`` replacing ``base``'s; neither argument is changed."""
    out = dict(base)
    for key, value in update.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge_tables(out[key], value)
        else:
            out[key] = value
    return out


# --------------------------------------------------------------------------- writing
def config_to_toml(config: ScenarioConfig, *, annotate: bool = False) -> str:
    """The fully resolved config as TOML text that :func:`load_config` reads back.

    With ``annotate``, every key is followed by a comment giving its meaning and unit and
    every table by its purpose (what ``hcomc config show`` prints).
    """
    data = config.model_dump(mode="json")
    if not annotate:
        return tomli_w.dumps(data)
    lines: list[str] = []
    _annotated(lines, type(config), data, prefix="")
    return "\n".join(lines) + "\n"


def _table_list(annotation: Any) -> type[BaseModel] | None:
    """The model of a list-of-tables annotation (``tuple[X, ...]``), if it is one."""
    if get_origin(annotation) not in (tuple, list):
        return None
    model = get_args(annotation)[0]
    return model if isinstance(model, type) and issubclass(model, BaseModel) else None


def _annotated(lines: list[str], model: type[BaseModel], data: dict[str, Any], prefix: str) -> None:
    tables, arrays = [], []
    for name, info in model.model_fields.items():
        sub = _sub_model(info.annotation)
        if sub is not None:
            tables.append((name, sub))
            continue
        entry_model = _table_list(info.annotation)
        if entry_model is not None and data[name]:
            arrays.append((name, entry_model))
            continue
        value = tomli_w.dumps({name: data[name]}).strip()
        if isinstance(data[name], dict):  # a free-form table, written inline
            entries = (tomli_w.dumps({k: v}).strip() for k, v in data[name].items())
            value = f"{name} = {{{', '.join(entries)}}}"
        elif isinstance(data[name], list):  # tomli_w spreads nested arrays over lines
            value = " ".join(value.split()).replace("[ ", "[").replace(", ]", "]")
        lines.append(f"{value}  # {info.description}" if info.description else value)
    for name, sub in tables:
        summary = (sub.__doc__ or "").strip().splitlines()[0]
        lines += ["", f"[{prefix}{name}]  # {summary}"]
        _annotated(lines, sub, data[name], prefix=f"{prefix}{name}.")
    for name, sub in arrays:  # TOML's [[name]]: after the tables
        summary = (sub.__doc__ or "").strip().splitlines()[0]
        for entry in data[name]:
            lines += ["", f"[[{prefix}{name}]]  # {summary}"]
            _annotated(lines, sub, entry, prefix=f"{prefix}{name}.")
