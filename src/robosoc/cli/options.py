"""The one place where command-line values are checked, before a command does any work.

Single values are checked while the command line is parsed, by callbacks declared next to the
option (the rules themselves are :mod:`robosoc.config.ranges`, shared with the library)::

    max_cycles: Annotated[int, typer.Option("--max-cycles", callback=options.int_range(1, MAX_CYCLES, "cycles"))]

A bad value stops the command with ``robosoc run: --max-cycles: must be between 1 and 2**62 cycles,
got -5`` (exit code 2), naming the option as it is written on the command line.  Checks that involve
several options, or a value and a configuration file, run first thing in the command body with
:func:`fail`, :func:`given`, :func:`exclusive`, :func:`parse_mesh`, :func:`parse_tile`,
:func:`parse_floats` and :func:`override`.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, TypeVar

import typer

from robosoc.cli.errors import CliError
from robosoc.config import ranges

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

T = TypeVar("T", bound="DataclassInstance")

__all__ = [
    "choice",
    "exclusive",
    "fail",
    "float_range",
    "given",
    "int_range",
    "option_name",
    "override",
    "parse_floats",
    "parse_mesh",
    "parse_tile",
    "pattern",
    "seed",
    "sram_bytes",
]

Callback = Callable[[typer.Context, typer.CallbackParam, Any], Any]


def fail(option: str, reason: str) -> CliError:
    """The error for a bad value of ``option``: ``raise options.fail("--off", "no core tile left")``."""
    return CliError(f"{option}: {reason}")


def option_name(param: typer.CallbackParam) -> str:
    """The option as written on the command line: its long name (``--max-cycles``)."""
    opts = list(getattr(param, "opts", ()) or ())
    long = [o for o in opts if o.startswith("--")]
    return (long or opts or [str(param.name)])[0]


def _checked(check: Callable[[str, Any], Any]) -> Callback:
    def callback(ctx: typer.Context, param: typer.CallbackParam, value: Any) -> Any:
        if value is None or getattr(ctx, "resilient_parsing", False):
            return value
        name = option_name(param)
        try:
            if isinstance(value, list | tuple):
                return type(value)(check(name, v) for v in value)
            return check(name, value)
        except ValueError as exc:
            raise CliError(str(exc)) from exc

    return callback


def checked(check: Callable[[str, Any], Any]) -> Callback:
    """A callback from ``check(option name, value)``, whose ``ValueError`` becomes the option's error."""
    return _checked(check)


def int_range(lo: int | None, hi: int | None = None, unit: str = "") -> Callback:
    """An integer in ``[lo, hi]`` (:func:`robosoc.config.ranges.check_int`)."""
    return _checked(lambda name, v: ranges.check_int(name, v, lo, hi, unit))


def float_range(lo: float | None, hi: float | None = None, *, lo_open: bool = False, unit: str = "") -> Callback:
    """A finite number in ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``); NaN and infinities refused."""
    return _checked(lambda name, v: ranges.check_float(name, v, lo, hi, lo_open=lo_open, unit=unit))


def seed() -> Callback:
    """A random seed in ``[0, 2**63-1]``."""
    return _checked(ranges.check_seed)


def sram_bytes() -> Callback:
    """An SRAM size: a multiple of 4 between 4096 and 2**30 bytes."""
    return _checked(ranges.check_sram_bytes)


def choice(*choices: str, normalize: Callable[[str], str] | None = None) -> Callback:
    """One of ``choices`` (after ``normalize``, which may itself raise ``ValueError``)."""

    def check(name: str, value: str) -> str:
        v = normalize(value) if normalize is not None else value
        if v not in choices:
            raise ValueError(f"{name}: must be one of {', '.join(choices)}, got {value!r}")
        return v

    return _checked(check)


def pattern(regex: str, expected: str) -> Callback:
    """Text matching ``regex`` as a whole; ``expected`` says what is wanted (``"NAME or NAME=VALUE"``)."""
    compiled = re.compile(regex, re.DOTALL)

    def check(name: str, value: str) -> str:
        if not compiled.fullmatch(value):
            raise ValueError(f"{name}: expected {expected}, got {value!r}")
        return value

    return _checked(check)


def given(ctx: typer.Context, name: str) -> bool:
    """Whether the user set parameter ``name`` (its Python name) on the command line or environment."""
    source = ctx.get_parameter_source(name)
    return source is not None and source.name in ("COMMANDLINE", "ENVIRONMENT")


def exclusive(**options: bool) -> None:
    """Refuse two or more of ``options`` (option name -> whether it was given) at once.

    A name in capitals is an argument's metavar (``LOG``) and is printed as it is.
    """
    names = [name.replace("_", "-") for name, on in options.items() if on]
    names = [n if n.startswith("--") or n.isupper() else f"--{n}" for n in names]
    if len(names) > 1:
        raise fail(names[0], f"cannot be combined with {' or '.join(names[1:])}")


def parse_mesh(option: str, text: str, min_tiles: int = 2) -> tuple[int, int]:
    """``"4x4"`` -> ``(4, 4)``: a mesh of 1..16 tiles per side and at least ``min_tiles`` tiles."""
    from robosoc.config.chip import MAX_MESH_SIDE

    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError as exc:
        raise fail(option, f"expected WxH such as 2x2, got {text!r}") from exc
    for what, v in (("width", width), ("height", height)):
        if not 1 <= v <= MAX_MESH_SIDE:
            raise fail(option, f"{what} must be between 1 and {MAX_MESH_SIDE} tiles, got {text!r}")
    if width * height < min_tiles:
        raise fail(option, f"a mesh needs at least {min_tiles} tiles, got {text!r}")
    return width, height


def parse_tile(option: str, text: str) -> tuple[int, int]:
    """``"1,1"`` -> ``(1, 1)``."""
    try:
        x, y = (int(v) for v in text.split(","))
    except ValueError as exc:
        raise fail(option, f"expected X,Y such as 1,1, got {text!r}") from exc
    if x < 0 or y < 0:
        raise fail(option, f"coordinates must be >= 0, got {text!r}")
    return x, y


def parse_floats(option: str, text: str, lo: float, hi: float, *, lo_open: bool = False) -> tuple[float, ...]:
    """``"0.1,0.2"`` -> ``(0.1, 0.2)``, each finite and in ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``)."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError as exc:
        raise fail(option, f"expected numbers separated by commas, got {text!r}") from exc
    for v in values:
        try:
            ranges.check_float(option, v, lo, hi, lo_open=lo_open)
        except ValueError as exc:
            raise CliError(f"{exc} (in {text!r})") from exc
    return values


def override(config: T, changes: dict[str, tuple[str, Any]], sources: Sequence[str] = ()) -> T:
    """``config`` with fields replaced from options, each error naming the option that set the field.

    Args:
        changes: option -> (dataclass field, value), e.g. ``{"--seconds": ("duration_s", 2.0)}``.
        sources: where the other values came from (files), named when a check that involves several
            fields fails on the combination.
    """
    for option, (field, value) in changes.items():
        try:
            config = dataclasses.replace(config, **{field: value})
        except (ValueError, TypeError) as exc:
            text = str(exc)
            for name, (other, _) in changes.items():
                match = re.match(rf"{re.escape(other)}(\[\d+\])?: ", text)
                if match:
                    text = f"{name}: {text[match.end() :]}"
                    break
            else:
                text = f"{option}: {text}"
            if sources:
                text += f" (with {', '.join(sources)})"
            raise CliError(text) from exc
    return config
