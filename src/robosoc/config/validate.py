"""Building frozen dataclasses from untyped mappings (TOML), with errors that name the field.

A config class is a ``@dataclass(frozen=True)`` whose fields carry type hints (int, float, bool,
str, tuples, nested dataclasses, ``X | None``) and, optionally, a ``__post_init__`` that raises
``ValueError("field: reason")`` for range checks.  :func:`from_mapping` rejects unknown keys,
converts types strictly (no bool where a number is meant, ints accepted for floats) and wraps
every failure in a :class:`ConfigError` whose message is ``<file>: <dotted.field>: <reason>``.

Merging is field by field: a mapping overrides only the fields it names and every other field
keeps its value in the *base* instance (by default ``cls()``, the class's defaults, including
defaults that a ``default_factory`` builds).  A table for a nested dataclass is merged the same
way into the base's nested instance; anything else, a list of tables included, replaces the
base's value as a whole (elements of a list are built from their class's defaults).
:func:`named_fields` lists the dotted fields a mapping sets, for provenance.
"""

from __future__ import annotations

import dataclasses
import tomllib
import types
import typing
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

T = TypeVar("T", bound="DataclassInstance")


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


def _convert(value: Any, hint: Any, path: str, where: str, base: Any = None) -> Any:
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if hint is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        options = [option for option in args if option is not type(None)]
        if len(options) == 1:  # ``X | None``: X's own error, naming the field inside it
            return _convert(value, options[0], path, where, base)
        errors = []
        for option in args:
            if option is type(None):
                continue
            try:
                return _convert(value, option, path, where, base)
            except ConfigError as exc:
                errors.append(exc.reason)
        raise ConfigError(where, path, "; ".join(errors))
    if origin is typing.Literal:
        if value not in args:
            raise ConfigError(where, path, f"must be one of {', '.join(map(repr, args))}, got {value!r}")
        return value
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):  # a class, never an instance
        if not isinstance(value, dict):
            raise ConfigError(where, path, f"expected a table, got {type(value).__name__}")
        return _build(hint, value, path, where, base if isinstance(base, hint) else None)
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


def _build(cls: type[T], data: dict[str, Any], path: str, where: str, base: T | None) -> T:
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ConfigError(where, _join(path, unknown[0]), f"unknown field (known: {', '.join(sorted(fields))})")
    kwargs: dict[str, Any] = {}
    for name, field in fields.items():
        if name not in data:
            if base is not None:
                kwargs[name] = getattr(base, name)
            elif field.default is dataclasses.MISSING and field.default_factory is dataclasses.MISSING:
                raise ConfigError(where, _join(path, name), "missing required field")
            continue
        inner = getattr(base, name) if base is not None else None
        kwargs[name] = _convert(data[name], hints[name], _join(path, name), where, inner)
    try:
        return cls(**kwargs)
    except ConfigError:
        raise
    except (ValueError, TypeError) as exc:
        text = str(exc)
        named, sep, reason = text.partition(": ")
        if sep and named.replace(".", "").replace("_", "").replace("[", "").replace("]", "").isalnum():
            raise ConfigError(where, _join(path, named), reason) from exc
        raise ConfigError(where, path, text) from exc


def _defaults(cls: type[T]) -> T | None:
    """``cls()``, or ``None`` if ``cls`` has required fields (or its defaults alone are no valid
    instance, as a project file without tasks)."""
    try:
        return cls()
    except (TypeError, ValueError):
        return None


def from_mapping(cls: type[T], data: dict[str, Any], where: str = "", base: T | None = None) -> T:
    """Build ``cls`` from a plain mapping merged field by field into ``base``, validating every field.

    Args:
        cls: a frozen dataclass type.
        data: the mapping (for example parsed TOML).
        where: a label for error messages (usually the file name).
        base: the instance whose values the fields ``data`` does not name keep (default:
            ``cls()`` if ``cls`` has no required field).

    Raises:
        ConfigError: naming ``where`` and the dotted field path.
    """
    return _build(cls, data, "", where, base if base is not None else _defaults(cls))


def named_fields(data: dict[str, Any], path: str = "") -> tuple[str, ...]:
    """The dotted fields a (validated) mapping sets: tables are descended, any other value,
    a list included, is one field.  In the mapping's order."""
    names: list[str] = []
    for name, value in data.items():
        if isinstance(value, dict):
            names.extend(named_fields(value, _join(path, name)))
        else:
            names.append(_join(path, name))
    return tuple(names)


def load_toml(cls: type[T], path: str | Path, section: str | None = None) -> T:
    """Read ``cls`` from a TOML file (optionally from one top-level table of it), merged field by
    field into ``cls()``.

    Raises:
        ConfigError: the file is missing or unreadable, is not valid TOML, or a field is wrong.
    """
    return load_toml_named(cls, path, section)[0]


def read_toml_mapping(path: str | Path, kind: str = "TOML file") -> dict[str, Any]:
    """Parse a TOML file into a plain mapping.

    Raises:
        ConfigError: the file is missing or unreadable, is not UTF-8 or not valid TOML.
    """
    return parse_toml_text(read_toml_text(path, kind), path)


def read_toml_text(path: str | Path, kind: str = "TOML file") -> str:
    """The text of a TOML file (:func:`parse_toml_text` parses it).

    Raises:
        ConfigError: the file is missing or unreadable, or is not UTF-8.
    """
    path = Path(path)
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError as exc:
        raise ConfigError(str(path), "", "file not found") from exc
    except IsADirectoryError as exc:
        raise ConfigError(str(path), "", f"is a folder, expected a {kind}") from exc
    except OSError as exc:
        raise ConfigError(str(path), "", f"cannot read: {exc.strerror or exc}") from exc
    except UnicodeDecodeError as exc:
        raise ConfigError(str(path), "", f"not UTF-8 text (offset {exc.start}): expected a TOML file") from exc


def parse_toml_text(text: str, path: str | Path) -> dict[str, Any]:
    """``text``, read from the file ``path``, as a plain mapping.

    Raises:
        ConfigError: not valid TOML (the file named).
    """
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(str(path), "", f"invalid TOML: {exc}") from exc


def load_toml_named(cls: type[T], path: str | Path, section: str | None = None) -> tuple[T, tuple[str, ...]]:
    """:func:`load_toml`, and the dotted fields the file sets (:func:`named_fields`)."""
    data = read_toml_mapping(path)
    if section is not None:
        if section not in data:
            raise ConfigError(str(path), section, "missing table")
        data = data[section]
    return from_mapping(cls, data, str(path)), named_fields(data)


def replace_checked(obj: T, **changes: Any) -> T:
    """``dataclasses.replace`` that re-runs validation and reports errors as :class:`ConfigError`."""
    try:
        return dataclasses.replace(obj, **changes)
    except ConfigError:
        raise
    except (ValueError, TypeError) as exc:
        raise ConfigError("", "", str(exc)) from exc
