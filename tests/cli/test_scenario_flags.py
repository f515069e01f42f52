"""The scenario flags (``robosoc.cli.scenario_flags``): one table from option to scenario field, one
resolver for every command; and ``robosoc serve``'s out folder and ``fly --decoupled``'s summary
numbers, called as library functions (no process, no socket).

Expectations from docs/cli.md: SCENARIO or ``--scenario`` (not both), ``--duration`` or its alias
``--seconds`` (not both), overrides named by the option as typed, a flight of at least one sensor
period, and an ``--out`` folder that is not an input file.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Annotated, Any

import pytest
import typer
from typer.testing import CliRunner

from robosoc.cli.errors import CliError
from robosoc.cli.scenario_flags import (
    FIRMWARE,
    FLAGS,
    FLY,
    SERVE_CHIP,
    ScenarioFlags,
    flags_of,
    resolve,
    takes_scenario,
)
from robosoc.cli.serve import _out
from robosoc.config.scenario import ScenarioConfig

SCENARIO = 'name = "hop"\nduration_s = 1.5\nseed = 11\n[flight]\ntakeoff_s = 0.3\nsteps = []\n'


@pytest.fixture
def scenario(tmp_path: Path) -> Path:
    path = tmp_path / "hop.toml"
    path.write_text(SCENARIO)
    return path


def resolved(option: Path | None = None, argument: Path | None = None, **values: Any) -> ScenarioConfig:
    return resolve(ScenarioFlags.of(option, argument, values)).config


def test_every_row_names_a_field_of_the_scenario_and_a_known_command() -> None:
    config = ScenarioConfig()
    for flag in FLAGS:
        node: Any = config
        for part in flag.field.split("."):
            assert dataclasses.is_dataclass(node) and part in {f.name for f in dataclasses.fields(node)}, flag
            node = getattr(node, part)
        assert flag.commands and set(flag.commands) <= {"fly", "serve physics", "serve chip", "firmware", "table"}, flag
        assert "firmware" not in flag.commands or flag.section == "firmware", flag  # firmware commands: no scenario
    assert len({f.param for f in FLAGS}) == len(FLAGS) and len({f.option for f in FLAGS}) == len(FLAGS)


def test_a_row_of_the_table_reaches_the_command_as_an_option_and_sets_its_field() -> None:
    """A command decorated with ``takes_scenario`` gets every row of its command as an option, and
    the resolver sets the row's field: what adding a row to the table gives every such command."""
    app = typer.Typer()
    seen: list[ScenarioConfig] = []

    @app.command()
    @takes_scenario(SERVE_CHIP)
    def cmd(flags: ScenarioFlags, other: int = 0) -> None:
        seen.append(resolve(flags).config)
        assert other == 3

    args = ["--other", "3", "--arith", "float", "--no-mul", "--duration", "0.5", "--seed", "8", "--vehicle", "laser"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    got = seen[0]
    assert (got.firmware.arith, got.firmware.multiplier, got.duration_s, got.seed, got.vehicle) == (
        "float",
        False,
        0.5,
        8,
        "laser",
    )
    assert CliRunner().invoke(app, ["--engine", "jit"]).exit_code != 0  # an option of fly, not of serve chip
    assert {f.option for f in flags_of(SERVE_CHIP)} < {f.option for f in flags_of(FLY)}


def test_the_file_alone_gives_its_fields(scenario: Path) -> None:
    flight = resolve(ScenarioFlags.of(None, scenario, {}))
    assert (flight.config.name, flight.config.duration_s, flight.config.seed, flight.path) == ("hop", 1.5, 11, scenario)
    assert flight.sources == ((str(scenario), ("name", "duration_s", "seed", "flight.takeoff_s", "flight.steps")),)


def test_the_option_and_the_argument_name_the_same_file(scenario: Path) -> None:
    assert resolved(option=scenario) == resolved(argument=scenario)
    with pytest.raises(CliError, match="--scenario"):
        ScenarioFlags.of(scenario, scenario, {})


def test_overrides_are_taken_named_as_sources_and_each_duration_option_works(scenario: Path) -> None:
    flight = resolve(ScenarioFlags.of(None, scenario, {"duration": 0.5, "vehicle": "laser", "seed": 4}))
    assert (flight.config.duration_s, flight.config.vehicle, flight.config.seed) == (0.5, "laser", 4)
    assert [source for source, _ in flight.sources] == [str(scenario), "--duration", "--seed", "--vehicle"]
    assert resolved(argument=scenario, seconds=0.25).duration_s == 0.25
    with pytest.raises(CliError, match=r"^--duration: cannot be combined with --seconds"):
        resolved(argument=scenario, duration=0.5, seconds=0.25)
    assert resolved(duration=0.75).duration_s == 0.75
    nested = resolved(arith="float", mul=False, engine="interp")
    assert (nested.firmware.arith, nested.firmware.multiplier, nested.chip.engine) == ("float", False, "interp")


@pytest.mark.parametrize(("option", "param"), [("--duration", "duration"), ("--seconds", "seconds")])
def test_a_flight_shorter_than_a_sensor_period_names_the_option(scenario: Path, option: str, param: str) -> None:
    with pytest.raises(CliError) as caught:
        resolved(argument=scenario, **{param: 0.001})
    assert caught.value.message == (
        f"{option}: a flight lasts at least one sensor period (0.01 s at 100 Hz), got 0.001 s (with {scenario})"
    )


def test_a_short_file_names_the_file_and_field(tmp_path: Path) -> None:
    short = tmp_path / "short.toml"
    short.write_text(SCENARIO.replace("duration_s = 1.5", "duration_s = 0.001"))
    with pytest.raises(CliError) as caught:
        resolved(argument=short)
    assert caught.value.message == (
        f"{short}: duration_s: a flight lasts at least one sensor period (0.01 s at 100 Hz), got 0.001 s"
    )
    with pytest.raises(CliError) as caught:
        resolved(option=short)
    assert caught.value.message.startswith(f"--scenario: {short}: duration_s: ")


def test_a_bad_value_is_named_by_its_option(scenario: Path) -> None:
    with pytest.raises(CliError, match=r"^--vehicle: "):
        resolved(argument=scenario, vehicle="blimp")
    with pytest.raises(CliError, match=r"^--arith: "):
        resolved(arith="double")
    with pytest.raises(CliError, match=r"^--engine: "):
        resolved(engine="fast")


def test_out_folder_default_and_rules(scenario: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert _out(None, True, "chip", "hop", 11, scenario) is None
    made = _out(None, False, "chip", "hop", 11, scenario)
    assert made is not None and made.resolve() == (tmp_path / "runs" / "serve-chip-hop-s11").resolve()
    with pytest.raises(CliError, match="--out"):
        _out(tmp_path / "x", True, "physics", "hop", 11, scenario)
    with pytest.raises(CliError, match=r"^--out: "):
        _out(scenario, False, "physics", "hop", 11, scenario)  # the input file itself


def test_decoupled_summary_numbers() -> None:
    from robosoc.cli.fly_decoupled import _number

    assert _number(0.0234, 100, "cm") == "2.34 cm"
    assert _number(-1.5, 1, "deg") == "-1.50 deg"
    assert _number(None, 100, "cm") == "n/a"
    assert _number(float("nan"), 100, "cm") == "n/a"
    assert _number(float("inf"), 1, "deg") == "n/a"


def test_an_error_about_a_field_names_who_set_it(tmp_path: Path) -> None:
    no_mul = tmp_path / "no-mul.toml"  # a chip whose cores have no multiplier, and a build without it
    no_mul.write_text("[firmware]\nmultiplier = false\n[chip.tile]\nmultiplier = false\n")
    with pytest.raises(CliError) as caught:
        resolved(argument=no_mul, mul=True)  # the scenario's own check, on a field the option set
    assert caught.value.message == (
        "--mul/--no-mul: the build uses the multiplier but task 'estimator' runs on [0, 1], which has none "
        f"(chip.tile or chip.tiles) (with {no_mul})"
    )
    with pytest.raises(CliError) as caught:
        resolved(argument=no_mul, arith="double")  # the firmware table's own check
    assert caught.value.message == f"--arith: must be one of 'float', 'fixed', got 'double' (with {no_mul})"
    flight = resolve(ScenarioFlags.of(None, no_mul, {"seed": 3}))
    assert flight.source_of("seed") == "--seed"
    assert flight.source_of("firmware.multiplier") == f"{no_mul}: firmware.multiplier"
    assert resolve(ScenarioFlags.of(None, None, {})).source_of("firmware.project") == "firmware.project"


def test_firmware_commands_take_the_firmware_rows_alone() -> None:
    from robosoc.cli.scenario_flags import FIRMWARE, resolve_section
    from robosoc.config.firmware import FirmwareConfig

    assert {f.option for f in flags_of(FIRMWARE)} == {"--arith", "--mul/--no-mul", "--fixed-mul", "--firmware"}
    base = FirmwareConfig(period_ticks=5)
    got = resolve_section(ScenarioFlags.of(None, None, {"arith": "float", "mul": False}), base, "firmware")
    assert (got.arith, got.multiplier, got.period_ticks) == ("float", False, 5)
    assert resolve_section(ScenarioFlags.of(None, None, {"arith": None}), base, "firmware") == base
    with pytest.raises(CliError, match=r"^--arith: must be one of"):
        resolve_section(ScenarioFlags.of(None, None, {"arith": "double"}), base, "firmware")


def test_the_decorator_places_the_scenario_file_after_the_commands_own_arguments(tmp_path: Path) -> None:
    """SCENARIO comes after the command's own arguments, --scenario is shown unless hidden, the
    annotations written as text are read, and a parameter that clashes with a flag is refused."""
    app = typer.Typer()
    seen: list[tuple[Any, ...]] = []

    @app.command()
    @takes_scenario(SERVE_CHIP, scenario_option_hidden=True)
    def hidden(flags: ScenarioFlags, name: Annotated[str, typer.Argument(metavar="NAME")], count: int = 1) -> None:
        seen.append((name, count, flags.path, flags.label, resolve(flags).config.duration_s))

    @app.command()
    @takes_scenario(FIRMWARE, scenario_file=False)
    def bare(flags: ScenarioFlags, top: int = 3) -> None:
        seen.append((top, dict(flags.values)))

    scenario = tmp_path / "s.toml"
    scenario.write_text("duration_s = 2.0\n")
    runner = CliRunner()
    result = runner.invoke(app, ["hidden", "first", str(scenario), "--count", "4"])
    assert result.exit_code == 0, result.output
    assert seen.pop() == ("first", 4, scenario, None, 2.0)
    result = runner.invoke(app, ["hidden", "first", "--scenario", str(scenario)])
    assert result.exit_code == 0 and seen.pop() == ("first", 1, scenario, "--scenario", 2.0)
    shown = runner.invoke(app, ["hidden", "--help"]).output
    assert "NAME" in shown and "SCENARIO" in shown and "--scenario" not in shown and "--arith" in shown
    assert shown.index("NAME") < shown.index("SCENARIO") and "Scenario TOML file" in shown
    assert runner.invoke(app, ["bare", "--arith", "float"]).exit_code == 0
    assert seen.pop() == (3, {"arith": "float", "mul": None, "fixed_mul": None, "firmware": None})
    bare_help = runner.invoke(app, ["bare", "--help"]).output
    assert "SCENARIO" not in bare_help and "--scenario" not in bare_help and "--seed" not in bare_help

    def clashing(flags: ScenarioFlags, seed: int = 0) -> None: ...

    with pytest.raises(TypeError, match=r"clashing: parameters \['seed'\] belong to the scenario flags"):
        takes_scenario(FLY)(clashing)


def test_the_fixed_point_multiply_routine_is_a_firmware_row() -> None:
    """--fixed-mul sets firmware.fixed_mul64 for every command that builds firmware, Table I included."""
    assert resolved(fixed_mul="muldi3").firmware.fixed_mul64 == "muldi3"
    assert resolved().firmware.fixed_mul64 == "shift-add"
    row = next(f for f in FLAGS if f.option == "--fixed-mul")
    assert row.field == "firmware.fixed_mul64" and set(row.commands) == {"fly", "serve chip", "firmware", "table"}
