"""Typed, validated configuration: every config in robosoc is a frozen dataclass checked here.

Use :func:`load_toml` to read a dataclass from a TOML file, or :func:`from_mapping` for a dict.
Errors are :class:`ConfigError` and name the file and the dotted field path.
"""

from robosoc.config.validate import ConfigError, from_mapping, load_toml, replace_checked

__all__ = ["ConfigError", "from_mapping", "load_toml", "replace_checked"]
