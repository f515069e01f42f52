"""Building frozen dataclasses from untyped mappings (TOML), with errors that name the field.

A config class is a ``@dataclass(frozen=True)`` whose fields carry type hints (int, float, bool,
str, tuples, nested dataclasses, ``X | None``) and, optionally, a ``__post_init__`` that raises
``ValueError("field: reason")`` for range checks.  :func:`from_mapping` rejects unknown keys,
converts types strictly (no bool where a number is meant, ints accepted for floats) and wraps
every failure in a :class:`ConfigError` whose message is ``<file>: <dotted.field>: <reason>``.
"""

from __future__ import annotations

import dataclasses
import tomllib
import types
import typing
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T")


class ConfigError(ValueError):
    """A configuration value is missing, unknown, of the wrong type or out of range."""

    def __init__(self, where: str, field: str, reason: str) -> None:
        self.where = where
        self.field = field
        self.reason = reason
        location = f"{where}: " if where else ""
        super().__init__(f"{location}{field or '<root>'}: {reason}")


def _join(path: str, name: str | int) -> str:
    if isinstance(name, int):
        return f"{path}[{name}]"
    return f"{path}.{name}" if path else name


def _convert(value: Any, hint: Any, path: str, where: str) -> Any:
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if hint is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        errors = []
        for option in args:
            if option is type(None):
                continue
            try:
                return _convert(value, option, path, where)
            except ConfigError as exc:
                errors.append(exc.reason)
        raise ConfigError(where, path, "; ".join(errors))
    if origin is typing.Literal:
        if value not in args:
            raise ConfigError(where, path, f"must be one of {', '.join(map(repr, args))}, got {value!r}")
        return value
    if dataclasses.is_dataclass(hint):
        if not isinstance(value, dict):
            raise ConfigError(where, path, f"expected a table, got {type(value).__name__}")
        return _build(hint, value, path, where)  # type: ignore[arg-type]
    if origin is tuple:
        if not isinstance(value, list | tuple):
            raise ConfigError(where, path, f"expected a list, got {type(value).__name__}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(v, args[0], _join(path, i), where) for i, v in enumerate(value))
        if len(value) != len(args):
            raise ConfigError(where, path, f"expected {len(args)} values, got {len(value)}")
        return tuple(_convert(v, a, _join(path, i), where) for i, (v, a) in enumerate(zip(value, args, strict=True)))
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(where, path, f"expected true or false, got {value!r}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(where, path, f"expected an integer, got {value!r}")
        return value
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(where, path, f"expected a number, got {value!r}")
        return float(value)
    if hint is str:
        if not isinstance(value, str):
            raise ConfigError(where, path, f"expected a string, got {value!r}")
        return value
    raise ConfigError(where, path, f"unsupported field type {hint!r}")


def _build(cls: type[T], data: dict[str, Any], path: str, where: str) -> T:
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}  # type: ignore[arg-type]
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ConfigError(where, _join(path, unknown[0]), f"unknown field (known: {', '.join(sorted(fields))})")
    kwargs: dict[str, Any] = {}
    for name, field in fields.items():
        if name not in data:
            if field.default is dataclasses.MISSING and field.default_factory is dataclasses.MISSING:
                raise ConfigError(where, _join(path, name), "missing required field")
            continue
        kwargs[name] = _convert(data[name], hints[name], _join(path, name), where)
    try:
        return cls(**kwargs)
    except ConfigError:
        raise
    except (ValueError, TypeError) as exc:
        text = str(exc)
        field, sep, reason = text.partition(": ")
        if sep and field.replace(".", "").replace("_", "").replace("[", "").replace("]", "").isalnum():
            raise ConfigError(where, _join(path, field), reason) from exc
        raise ConfigError(where, path, text) from exc


def from_mapping(cls: type[T], data: dict[str, Any], where: str = "") -> T:
    """Build ``cls`` from a plain mapping, validating every field.

    Args:
        cls: a frozen dataclass type.
        data: the mapping (for example parsed TOML).
        where: a label for error messages (usually the file name).

    Raises:
        ConfigError: naming ``where`` and the dotted field path.
    """
    return _build(cls, data, "", where)


def load_toml(cls: type[T], path: str | Path, section: str | None = None) -> T:
    """Read ``cls`` from a TOML file (optionally from one top-level table of it).

    Raises:
        ConfigError: the file is missing or unreadable, is not valid TOML, or a field is wrong.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except FileNotFoundError as exc:
        raise ConfigError(str(path), "", "file not found") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(str(path), "", f"invalid TOML: {exc}") from exc
    if section is not None:
        if section not in data:
            raise ConfigError(str(path), section, "missing table")
        data = data[section]
    return from_mapping(cls, data, str(path))


def replace_checked(obj: T, **changes: Any) -> T:
    """``dataclasses.replace`` that re-runs validation and reports errors as :class:`ConfigError`."""
    try:
        return dataclasses.replace(obj, **changes)  # type: ignore[type-var]
    except ConfigError:
        raise
    except (ValueError, TypeError) as exc:
        raise ConfigError("", "", str(exc)) from exc
