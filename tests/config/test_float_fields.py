"""Every float field of every configuration file has a finite range with units (config/ranges.py,
issue 34 item 2): NaN, infinities, huge, tiny and negative values are refused with a ConfigError
naming the file and the field, or accepted with a finite value in the range; never a traceback or
a hang (clock_period_ns = 1e-9 simulated forever, sensor sigmas of 1e300 broke the Q16.16 packing,
pj = nan printed "energy nan nJ")."""

from __future__ import annotations

import dataclasses
import math
import re
import types
import typing
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from robosoc.chip.energy import INSTRUCTION_CLASSES, NOC_TERMS, STALL_KINDS, EnergyModel
from robosoc.cli import app, exit_codes
from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.link import LinkConfig
from robosoc.config.ranges import FLOAT_FIELDS
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.validate import ConfigError, from_mapping
from robosoc.config.vehicle import VehicleConfig

ROOTS = (ScenarioConfig, ChipConfig, FirmwareConfig, VehicleConfig, LinkConfig)
"""The configuration files: scenario (its chip and firmware tables included), chip, firmware, vehicle,
link; sweep files set scenario fields.  The energy coefficients are checked separately below."""

ABSURD = st.sampled_from(
    [math.nan, math.inf, -math.inf, 1e300, -1e300, 1e-300, -1e-300, 1e-9, -1e-9, 0.0, -0.0, -1.0, 1e9, 2.0**63]
)
FLOATS = st.one_of(ABSURD, st.floats(allow_nan=True, allow_infinity=True), st.integers(-(2**70), 2**70))


def _floaty(hint: Any) -> str | None:
    """'scalar' or 'vector' for float fields (optional ones included), else None."""
    if hint is float:
        return "scalar"
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        kinds = {_floaty(a) for a in args if a is not type(None)}
        return kinds.pop() if len(kinds) == 1 else None
    if origin is tuple and args and all(a is float or a is Ellipsis for a in args):
        return "vector"
    return None


def _element(hint: Any) -> Any:
    """The dataclass inside ``tuple[X, ...]``, ``X | None`` or ``X``."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin is tuple and len(args) == 2 and args[1] is Ellipsis and dataclasses.is_dataclass(args[0]):
        return args[0]
    return hint if dataclasses.is_dataclass(hint) else None


def float_fields(cls: type, prefix: str = "") -> list[tuple[str, str, str]]:
    """(dotted path with [0] for list elements, "<Class>.<field>", scalar|vector) of every float field."""
    out = []
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        hint = hints[f.name]
        kind = _floaty(hint)
        if kind is not None:
            out.append((f"{prefix}{f.name}", f"{cls.__name__}.{f.name}", kind))
            continue
        inner = _element(hint)
        if inner is not None:
            listed = typing.get_origin(hint) is tuple
            out.extend(float_fields(inner, f"{prefix}{f.name}{'[0]' if listed else ''}."))
    return out


FIELDS = sorted({(root, *field) for root in ROOTS for field in float_fields(root)}, key=lambda f: (f[0].__name__, f[1]))


#: Dataclasses of robosoc.config that no file sets (so their floats need no file range), and why.
NOT_READ_FROM_FILES = {"HeightMove": "worked out from a flight plan (FlightPlan.height_moves), never read"}


def _config_dataclasses() -> list[type]:
    """Every dataclass defined in a module of robosoc.config (a new configuration file included)."""
    import importlib
    import inspect
    import pkgutil

    import robosoc.config

    found = []
    for info in pkgutil.iter_modules(robosoc.config.__path__):
        module = importlib.import_module(f"robosoc.config.{info.name}")
        found += [
            c for _, c in inspect.getmembers(module, inspect.isclass)
            if dataclasses.is_dataclass(c) and c.__module__ == module.__name__ and c.__name__ not in NOT_READ_FROM_FILES
        ]  # fmt: skip
    return found


def test_every_float_field_of_every_configuration_has_a_range_with_a_unit_or_a_reason() -> None:
    every = {owner for cls in _config_dataclasses() for _, owner, _ in float_fields(cls)}
    assert {"TileConfig.clock_period_ns", "SensorConfig.accel_sigma"} <= every  # the walk sees them
    missing = sorted((every | {owner for _, _, owner, _ in FIELDS}) - set(FLOAT_FIELDS))
    assert not missing, f"float fields without a range in config/ranges.py FLOAT_FIELDS: {missing}"
    assert {"Coefficient.pj", "EnergyModel.clock_ns"} <= set(FLOAT_FIELDS)
    for name, rule in FLOAT_FIELDS.items():
        assert math.isfinite(rule.lo) and math.isfinite(rule.hi) and rule.lo < rule.hi, name
    assert len(FIELDS) > 50  # scenario, chip, vehicle, link: the walk found them


def _mapping(path: str, value: Any, owner: str) -> dict[str, Any]:
    """The smallest file table setting ``path`` (list elements get their required fields)."""
    required = {"TileOverride": {"x": 0, "y": 0}, "SetpointStep": {"time_s": 9.0, "axis": "height", "value": 1.0}}
    parts = path.split(".")
    leaf: dict[str, Any] = {parts[-1]: value}
    cls_name = owner.split(".")[0]
    for part in reversed(parts[:-1]):
        m = re.fullmatch(r"(\w+)\[0\]", part)
        if m:
            element = {**required.get(cls_name, {}), **leaf}
            leaf = {m.group(1): [element]}
        else:
            leaf = {part: leaf}
    return leaf


def _value_at(config: Any, path: str) -> Any:
    for part in path.split("."):
        m = re.fullmatch(r"(\w+)\[0\]", part)
        config = getattr(config, m.group(1))[0] if m else getattr(config, part)
    return config


@pytest.mark.parametrize(("root", "path", "owner", "kind"), FIELDS, ids=[f"{r.__name__}:{p}" for r, p, _, _ in FIELDS])
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(value=FLOATS, position=st.integers(0, 2))
def test_absurd_numbers_in_any_float_field_are_refused_or_in_range(root, path, owner, kind, value, position) -> None:
    default = _value_at(root(), path) if "[0]" not in path else None
    if kind == "vector":
        vector = list(default) if default is not None else [0.0, 0.0, 0.0]
        vector[position % len(vector)] = value
        given_value: Any = vector
    else:
        given_value = value
    try:
        config = from_mapping(root, _mapping(path, given_value, owner), "file.toml")
    except ConfigError as exc:
        assert str(exc).startswith("file.toml: "), exc
        parent = path.rpartition(".")[0]  # the field, or another of its table (a rule across fields)
        assert exc.field.startswith(parent), (exc, path)
        return
    rule = FLOAT_FIELDS[owner]
    got = _value_at(config, path)
    values = got if isinstance(got, tuple) else (got,)
    for v in values:
        assert isinstance(v, float) and math.isfinite(v) and rule.lo <= v <= rule.hi, (path, v, rule)


# --- the energy coefficients file -------------------------------------------------------------------


ENERGY_DEFAULT = (Path(__file__).parents[2] / "src/robosoc/chip/energy_coefficients.toml").read_text()
ENERGY_KEYS = [
    *(f"instruction.{k}" for k in INSTRUCTION_CLASSES),
    *(f"stall.{k}" for k in STALL_KINDS),
    *(f"noc.{k}" for k in NOC_TERMS),
]


def _toml_float(value: float | int) -> str:
    if isinstance(value, int):
        return str(value)
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return repr(value)


def _energy_file(tmp_path: Path, key: str, value: float | int) -> Path:
    text = ENERGY_DEFAULT
    if key == "clock_ns":
        text = re.sub(r"(?m)^clock_ns = .*$", f"clock_ns = {_toml_float(value)}", text)
    else:
        text = re.sub(rf"(?ms)^(\[{re.escape(key)}\]\npj = )[^\n]*", rf"\g<1>{_toml_float(value)}", text)
    path = tmp_path / "energy.toml"
    path.write_text(text)
    return path


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(key=st.sampled_from(["clock_ns", *ENERGY_KEYS]), value=FLOATS)
def test_absurd_energy_coefficients_are_refused_or_finite(tmp_path: Path, key: str, value: float) -> None:
    path = _energy_file(tmp_path, key, value)
    try:
        model = EnergyModel.load(path)
    except ConfigError as exc:
        assert str(exc).startswith(f"{path}: {key}"), exc
        return
    assert math.isfinite(model.clock_ns)
    counts = dict.fromkeys([*INSTRUCTION_CLASSES, *STALL_KINDS], 10**9)
    assert math.isfinite(model.total_nj(counts))


# --- the reported cases, as a user meets them ---------------------------------------------------------

runner = CliRunner()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[sensors]\naccel_sigma = [1e300, 0.3, 0.3]\n", "sensors.accel_sigma[0]: must be in [0, 20] m/s², got 1e+300"),
        ("[sensors]\nbaro_sigma = 1e300\n", "sensors.baro_sigma: must be in [0, 100] m, got 1e+300"),
        ("[chip.tile]\nclock_period_ns = 1e-9\n", "chip.tile.clock_period_ns: must be in [0.5, 1000] ns, got 1e-09"),
        ("[chip.tile]\nclock_period_ns = 1e300\n", "chip.tile.clock_period_ns: must be in [0.5, 1000] ns, got 1e+300"),
        ("[chip.tile]\nclock_period_ns = inf\n", "chip.tile.clock_period_ns: must be a finite number, got inf"),
        ("[wind]\ngust_tau_s = 1e300\n", "wind.gust_tau_s: must be in [0.001, 3600] s, got 1e+300"),
    ],
)
def test_scenario_files_with_absurd_numbers_are_refused(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    for args in (["scenario", "show", path], ["fly", path, "--no-out"]):
        result = runner.invoke(app, [str(a) for a in args])
        assert result.exit_code == exit_codes.USAGE, result.output
        command = "scenario show" if args[0] == "scenario" else "fly"
        assert result.output.splitlines()[0] == f"robosoc {command}: {path}: {message}", result.output


@pytest.mark.parametrize("value", ["nan", "inf", "1e300", "1e-9", "-1"])
def test_run_refuses_absurd_chip_clocks_and_energy_coefficients(tmp_path: Path, value: str) -> None:
    chip = tmp_path / "chip.toml"
    chip.write_text(f"width = 2\nheight = 1\n[tile]\nclock_period_ns = {value}\n")
    energy = _energy_file(tmp_path, "instruction.jump", float(value))
    elf = tmp_path / "none.elf"  # never read: the files are refused first
    elf.write_bytes(b"\x7fELF")
    cases = [([elf, "--chip", chip], f"--chip: {chip}: tile.clock_period_ns: ")]
    if value != "1e-9":  # 1e-9 pJ is a (tiny) energy
        cases.append(([elf, "--energy", energy], f"--energy: {energy}: instruction.jump.pj: "))
    for args, where in cases:
        result = runner.invoke(app, ["run", *map(str, args)])
        if value == "-1" and "--energy" in args:
            assert "expected a non-negative number" in result.output
        assert result.exit_code == exit_codes.USAGE, result.output
        assert where in result.output.splitlines()[0], result.output


# --- the same through the command line: a file on disk, one line, exit 0 or 2 ---------------------------


def _toml_value(value: Any) -> str:
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + " }"
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bool):
        return "true" if value else "false"
    return _toml_float(value)


def _toml(mapping: dict[str, Any]) -> str:
    return "".join(f"{key} = {_toml_value(value)}\n" for key, value in mapping.items())


CLI_FIELDS = [f for f in FIELDS if f[0] in (ScenarioConfig, ChipConfig)]


@pytest.mark.parametrize(
    ("root", "path", "owner", "kind"), CLI_FIELDS, ids=[f"{r.__name__}:{p}" for r, p, _, _ in CLI_FIELDS]
)
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(value=FLOATS)
def test_absurd_numbers_in_files_are_one_line_and_exit_2_on_the_command_line(
    tmp_path: Path, root, path, owner, kind, value
) -> None:
    given_value: Any = [value, value, value] if kind == "vector" else value
    file = tmp_path / "f.toml"
    file.write_text(_toml(_mapping(path, given_value, owner)), encoding="utf-8")
    elf = tmp_path / "none.elf"
    elf.write_bytes(b"\x7fELF")
    if root is ScenarioConfig:
        args, command = ["scenario", "show", str(file)], "robosoc scenario show"
    else:
        args, command = ["run", str(elf), "--chip", str(file)], "robosoc run"
    result = runner.invoke(app, args)
    assert "Traceback" not in result.output and "internal error" not in result.output, result.output
    if result.exit_code == 0:
        assert root is ScenarioConfig
        return
    assert result.exit_code == exit_codes.USAGE, result.output
    first = result.output.splitlines()[0]
    assert first.startswith(f"{command}: "), first
    if root is ChipConfig and str(elf) in first:
        return  # the chip file was accepted: the (fake) program is what is refused
    assert str(file) in first, first
