"""The scenario's dotted field names (``firmware.arith``): listing them, and checking a name.

Sweep files and a project's ``[scenario]`` defaults name scenario fields this way; a name that is
no field (or a whole table) is an error that lists what the table has.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from typing import TYPE_CHECKING, Any

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.validate import ConfigError

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

__all__ = ["SEED_FIELD", "check_field", "field_names"]

SEED_FIELD = "seed"
"""The scenario's seed: a sweep sets it from its ``seeds`` list, never from a grid or a point."""


def field_names(cls: type[DataclassInstance] | DataclassInstance = ScenarioConfig, prefix: str = "") -> list[str]:
    """Every dotted field of ``cls``, nested dataclasses descended."""
    names: list[str] = []
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        hint = hints[f.name]
        if dataclasses.is_dataclass(hint):
            names.extend(field_names(hint, f"{prefix}{f.name}."))
        else:
            names.append(f"{prefix}{f.name}")
    return names


def _table(hint: Any) -> Any:
    """The dataclass of an optional table (``MissionPlan | None``), else ``hint`` itself."""
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        tables = [a for a in typing.get_args(hint) if dataclasses.is_dataclass(a)]
        if len(tables) == 1:
            return tables[0]
    return hint


def check_field(name: str, where: str, key: str, verb: str = "name") -> None:
    """Raise :class:`ConfigError` (``where``, ``key``) unless ``name`` is a dotted field of the
    scenario that holds a value (not a table); ``verb`` says what the file does with it."""
    cls: Any = ScenarioConfig
    parts = name.split(".")
    for i, part in enumerate(parts):
        hints = typing.get_type_hints(cls) if dataclasses.is_dataclass(cls) else {}
        if part not in hints:
            known = ", ".join(sorted(hints)) if hints else "none: it is not a table"
            parent = ".".join(parts[:i]) or "the scenario"
            raise ConfigError(where, key, f"{name!r} is not a scenario field ({parent} has: {known})")
        cls = _table(hints[part])
    if dataclasses.is_dataclass(cls):
        raise ConfigError(where, key, f"{name!r} is a table; {verb} one of its fields ({', '.join(field_names(cls))})")
