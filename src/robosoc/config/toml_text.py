"""Writing a config dataclass as TOML text that :func:`robosoc.config.validate.from_mapping` reads back.

The inverse of the loader for the config classes of this package (frozen dataclasses whose fields
are bool, int, float, str, tuples of these, nested dataclasses, tuples of dataclasses and optional
values): every field is written, so the text shows the whole resolved configuration and loading it
gives an equal object.  Layout: a table's plain values first, then its nested tables (``[a.b]``),
then its lists of tables (``[[a.c]]``); an empty list of tables is written ``c = []``; a field
holding ``None`` is left out (such fields default to ``None``).
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

__all__ = ["to_toml"]


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a TOML basic string (\uXXXX escapes included)
    if isinstance(value, tuple | list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def _is_table_list(value: Any) -> bool:
    return isinstance(value, tuple | list) and bool(value) and all(dataclasses.is_dataclass(v) for v in value)


def _table(obj: Any, path: str, lines: list[str]) -> None:
    fields = [(f.name, getattr(obj, f.name)) for f in dataclasses.fields(obj) if f.init]
    for name, value in fields:
        if value is None or dataclasses.is_dataclass(value) or _is_table_list(value):
            continue
        lines.append(f"{name} = {_value(value)}")
    for name, value in fields:
        if dataclasses.is_dataclass(value):
            lines.extend(("", f"[{path}{name}]"))
            _table(value, f"{path}{name}.", lines)
    for name, value in fields:
        if _is_table_list(value):
            for item in value:
                lines.extend(("", f"[[{path}{name}]]"))
                _table(item, f"{path}{name}.", lines)


def to_toml(config: Any, header: str = "") -> str:
    """Every field of the dataclass instance ``config`` as TOML; ``header`` lines become comments.

    Raises:
        TypeError: ``config`` is not a dataclass instance, or a field holds a value TOML cannot hold.
    """
    if not dataclasses.is_dataclass(config) or isinstance(config, type):
        raise TypeError(f"expected a dataclass instance, got {type(config).__name__}")
    lines = [f"# {line}".rstrip() for line in header.splitlines()]
    _table(config, "", lines)
    return "\n".join(lines).lstrip("\n") + "\n"
