"""Dotted field names: nested TOML tables as ``a.b`` keys and back.

A sweep's points, a project's scenario defaults and a scenario file all name fields this way
(``firmware.arith``); merging two flat mappings then merges field by field, a list as a whole.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

__all__ = ["flatten", "nest"]


def flatten(table: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested TOML tables as dotted names: ``{"a": {"b": 1}}`` → ``{"a.b": 1}``."""
    flat: dict[str, Any] = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flatten(value, f"{name}."))
        else:
            flat[name] = value
    return flat


def nest(assignment: Mapping[str, Any] | Iterable[tuple[str, Any]]) -> dict[str, Any]:
    """Dotted names back to nested tables, as :func:`robosoc.config.validate.from_mapping` takes."""
    items = assignment.items() if isinstance(assignment, Mapping) else assignment
    tree: dict[str, Any] = {}
    for name, value in items:
        *tables, leaf = name.split(".")
        node = tree
        for table in tables:
            node = node.setdefault(table, {})
        node[leaf] = value
    return tree
