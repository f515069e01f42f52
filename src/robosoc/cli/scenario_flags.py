"""The command-line flags that set a scenario's fields: one table, and one resolver for every command.

Each row of :data:`FLAGS` says which option sets which (dotted) field of
:class:`robosoc.config.scenario.ScenarioConfig`, how the option is declared, and which commands take
it.  :func:`takes_scenario` gives a command the scenario file (``SCENARIO`` or ``--scenario``) and its
rows as options, and hands the command one :class:`ScenarioFlags` instead; :func:`resolve` turns
that into the scenario: the built-in default, the file merged into it, then the options, each error
naming the option as typed, the file or the field.  Adding a flag that sets a scenario field is a new
row here, and nothing else.
"""

from __future__ import annotations

import functools
import inspect
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer

from robosoc.cli import options
from robosoc.cli.engine_option import Engine
from robosoc.cli.errors import CliError
from robosoc.config.firmware import ARITH_CHOICES, FIXED_MUL64_CHOICES
from robosoc.config.power import SUPPLIES
from robosoc.config.project_scenario import PROJECT_FIELD
from robosoc.config.scenario import CONTROLLERS, MAX_VEHICLES
from robosoc.config.vehicle import VEHICLE_PRESETS

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

    from robosoc.config.scenario import ScenarioConfig

FLY = "fly"
SERVE_PHYSICS = "serve physics"
SERVE_CHIP = "serve chip"
FIRMWARE = "firmware"  # build, size, replay: they take the firmware section's rows alone
TABLE = "table"
_EVERY = (FLY, SERVE_PHYSICS, SERVE_CHIP)

DURATION_HELP = (
    "Flight length in seconds, whole ms in 0.001..3600, at least one sensor period (default: the scenario's)."
)
SCENARIO_HELP = "Scenario TOML file (default: built-in; robosoc scenario show prints every field)."


@dataclass(frozen=True)
class ScenarioFlag:
    """One option that sets one scenario field.

    Attributes:
        option: as typed on the command line (``--mul/--no-mul`` for a pair).
        param: its Python parameter name.
        field: the scenario field it sets, dotted (``firmware.arith``).
        annotation: the typer declaration (type, help, check).
        commands: the commands that take it.
    """

    option: str
    param: str
    field: str
    annotation: Any
    commands: tuple[str, ...] = _EVERY

    @property
    def section(self) -> str | None:
        """The sub-table the field lives in (``firmware``, ``chip``), None for a top-level field."""
        head, dot, _ = self.field.partition(".")
        return head if dot else None


Controller = Annotated[
    str | None,
    typer.Option(
        help="Who flies: chip (the firmware on the chip, in lockstep) or host (float64 Python) "
        "(default: the scenario's, chip).",
        callback=options.choice(*CONTROLLERS),
    ),
]
Duration = Annotated[
    float | None, typer.Option(help=DURATION_HELP, callback=options.float_range(0.001, 3600.0, unit="s"))
]
Seconds = Annotated[
    float | None, typer.Option(help=DURATION_HELP, callback=options.float_range(0.001, 3600.0, unit="s"), hidden=True)
]
Seed = Annotated[
    int | None,
    typer.Option(
        help="Seeds every random number (noise, biases, gusts), 0..2**63-1 (default: the scenario's, 1).",
        callback=options.seed(),
    ),
]
Vehicle = Annotated[
    str | None,
    typer.Option(help="default or laser (default: the scenario's).", callback=options.choice(*VEHICLE_PRESETS)),
]
Vehicles = Annotated[
    int | None,
    typer.Option(
        help=f"Quadrotors in one world, 1..{MAX_VEHICLES}, each with its own chip (default: the scenario's, 1).",
        callback=options.int_range(1, MAX_VEHICLES),
    ),
]
Arith = Annotated[
    str | None,
    typer.Option(
        help="Firmware arithmetic: float (soft-float) or fixed (Q16.16) "
        "(default: the scenario's or --config's, fixed).",
        callback=options.choice(*ARITH_CHOICES),
    ),
]
Mul = Annotated[
    bool | None,
    typer.Option(
        "--mul/--no-mul",
        help="Firmware built for cores with the multiplier or without (default: the scenario's or --config's, with).",
    ),
]


def _folder(ctx: typer.Context, param: typer.CallbackParam, value: str | None) -> str | None:
    """A folder given on the command line, made absolute (it is kept in the run's scenario.toml)."""
    return None if value is None else str(Path(value).expanduser().absolute())


Firmware = Annotated[
    str | None,
    typer.Option(
        metavar="DIR",
        help="The firmware project in DIR (its robosoc.toml: robosoc new DIR makes one; its chip and "
        "scenario tables are the defaults) instead of the shipped quadrotor project (default: the "
        "scenario's firmware.project).",
        callback=_folder,
    ),
]
FixedMul = Annotated[
    str | None,
    typer.Option(
        "--fixed-mul",
        help="Q16.16 multiply in the builds without the multiplier: shift-add (robosoc's routine) or muldi3 "
        "(the 64-bit product through compiler-rt's __muldi3, as HellfireOS) (default: the scenario's, shift-add).",
        callback=options.choice(*FIXED_MUL64_CHOICES),
    ),
]
Supply = Annotated[
    str | None,
    typer.Option(
        help="What feeds the motors: constant (14.8 V) or battery (the scenario's [power.battery] Li-Po pack, "
        "and a power budget in flight.csv, summary.json and the report; docs/power.md) "
        "(default: the scenario's, constant).",
        callback=options.choice(*SUPPLIES),
    ),
]
NocGating = Annotated[
    bool | None,
    typer.Option(
        "--noc-gating/--no-noc-gating",
        help="Routers that held no flit for chip.noc.gate_after_cycles stop their clock, and wake up "
        "chip.noc.wake_cycles later when a flit arrives (default: the scenario's, off; docs/noc.md).",
    ),
]
ScenarioArg = Annotated[Path | None, typer.Argument(metavar="SCENARIO", help=SCENARIO_HELP, show_default=False)]

FLAGS: tuple[ScenarioFlag, ...] = (
    ScenarioFlag("--controller", "controller", "controller", Controller, (FLY,)),
    ScenarioFlag("--duration", "duration", "duration_s", Duration),
    ScenarioFlag("--seconds", "seconds", "duration_s", Seconds),
    ScenarioFlag("--seed", "seed", "seed", Seed, (*_EVERY, TABLE)),
    ScenarioFlag("--vehicle", "vehicle", "vehicle", Vehicle),
    ScenarioFlag("--vehicles", "vehicles", "vehicles", Vehicles, (FLY, SERVE_PHYSICS)),
    ScenarioFlag("--arith", "arith", "firmware.arith", Arith, (FLY, SERVE_CHIP, FIRMWARE)),
    ScenarioFlag("--mul/--no-mul", "mul", "firmware.multiplier", Mul, (FLY, SERVE_CHIP, FIRMWARE)),
    ScenarioFlag("--fixed-mul", "fixed_mul", "firmware.fixed_mul64", FixedMul, (FLY, SERVE_CHIP, FIRMWARE, TABLE)),
    ScenarioFlag("--engine", "engine", "chip.engine", Engine, (FLY,)),
    ScenarioFlag("--firmware", "firmware", "firmware.project", Firmware, (*_EVERY, FIRMWARE, TABLE)),
    ScenarioFlag("--supply", "supply", "power.supply", Supply, (FLY,)),
    ScenarioFlag("--noc-gating/--no-noc-gating", "noc_gating", "chip.noc.clock_gating", NocGating, (FLY,)),
)
"""Every flag that sets a scenario field."""


@dataclass(frozen=True)
class ScenarioFlags:
    """What a command was given: the scenario file (and how it was named) and the flags' values
    (``None``: not given)."""

    path: Path | None
    label: str | None
    values: Mapping[str, Any]

    @classmethod
    def of(cls, option: Path | None, argument: Path | None, values: Mapping[str, Any]) -> ScenarioFlags:
        """The flags of a command line: the scenario file given as ``--scenario`` or as ``SCENARIO``
        (not both; errors then name ``--scenario``, or the file alone)."""
        options.exclusive(scenario=option is not None, SCENARIO=argument is not None)
        if option is not None:
            return cls(option, "--scenario", dict(values))
        return cls(argument, None, dict(values))

    def given(self) -> list[ScenarioFlag]:
        """The rows whose option was given, in table order."""
        return [flag for flag in FLAGS if self.values.get(flag.param) is not None]


@dataclass(frozen=True)
class ResolvedScenario:
    """A scenario as a command flies it, and where each part came from.

    Attributes:
        config: the scenario: default, file, options.
        path: the scenario file (None: built in).
        given: the flags the user gave.
        sources: (source, fields it set) in order: the file, then each option.
    """

    config: ScenarioConfig
    path: Path | None
    given: tuple[ScenarioFlag, ...]
    sources: tuple[tuple[str, tuple[str, ...]], ...]

    def source_of(self, field: str) -> str:
        """Who set a dotted field, for an error about its value: the option as typed, else the
        scenario file and the field, else the field (a default)."""
        for flag in self.given:
            if flag.field == field:
                return flag.option
        return f"{self.path}: {field}" if self.path is not None else field

    @property
    def inputs(self) -> list[Path]:
        """Files the command reads (an output must not overwrite them)."""
        return [self.path] if self.path is not None else []


def flags_of(command: str) -> tuple[ScenarioFlag, ...]:
    return tuple(flag for flag in FLAGS if command in flag.commands)


def resolve(flags: ScenarioFlags) -> ResolvedScenario:
    """The scenario of ``flags``: the built-in default, the file's fields, then the options.

    Raises:
        CliError: an unreadable or invalid file (file and field named), two options for one field,
            or a value that the scenario refuses (the option named).
    """

    given = flags.given()
    by_field: dict[str, list[str]] = {}
    for flag in given:
        by_field.setdefault(flag.field, []).append(flag.option)
    for names in by_field.values():
        if len(names) > 1:
            raise options.fail(names[0], f"cannot be combined with {' or '.join(names[1:])}")
    config, named = _file_scenario(flags, next((f for f in given if f.field == PROJECT_FIELD), None))
    sources = [(str(flags.path), named)] if flags.path is not None else []
    file_names = [str(flags.path)] if flags.path is not None else []
    config = override(config, {flag.option: (flag.field, flags.values[flag.param]) for flag in given}, file_names)
    sources += [(flag.option, (flag.field,)) for flag in given]
    return ResolvedScenario(config, flags.path, tuple(given), tuple(sources))


def _file_scenario(flags: ScenarioFlags, project_flag: ScenarioFlag | None) -> tuple[ScenarioConfig, tuple[str, ...]]:
    """The scenario file's fields (none without a file) over the defaults of the project flown
    (:mod:`robosoc.config.project_scenario`: the option's project if given, else the file's, whose
    relative folder is the file's neighbour), and the dotted fields the file sets."""
    from robosoc.cli import files
    from robosoc.config.project_scenario import project_beside, project_scenario
    from robosoc.config.scenario import ScenarioConfig
    from robosoc.config.validate import ConfigError, from_mapping, named_fields

    data: dict[str, Any] = {}
    if flags.path is not None:
        data = files.read_toml(flags.path, flags.label)
    firmware = data.get("firmware")
    project: Any = ""
    if isinstance(firmware, dict) and "project" in firmware and flags.path is not None:
        project = project_beside(firmware["project"], flags.path.parent)  # a project named by a file: its neighbour
        data = {**data, "firmware": {**firmware, "project": project}}
    source = f"{flags.label + ': ' if flags.label else ''}{flags.path}: {PROJECT_FIELD}"
    if project_flag is not None:  # the option's project: its defaults, under the file's other fields
        project, source = flags.values[project_flag.param], project_flag.option
        if isinstance(firmware, dict) and "project" in firmware:
            data = {**data, "firmware": {k: v for k, v in firmware.items() if k != "project"}}
    try:
        base = project_scenario(project if isinstance(project, str) else "")  # a wrong type: the file's error below
    except ConfigError as exc:
        reason = exc.reason if exc.field == PROJECT_FIELD and not exc.where else str(exc)
        raise CliError(f"{source}: {reason}") from exc
    if flags.path is None:
        return base, ()
    try:
        return from_mapping(ScenarioConfig, data, str(flags.path), base=base), named_fields(data)
    except ConfigError as exc:
        raise CliError(f"{flags.label}: {exc}" if flags.label else str(exc)) from exc


C = TypeVar("C", bound="DataclassInstance")


def resolve_section(flags: ScenarioFlags, base: C, section: str) -> C:
    """``base`` (a scenario's sub-table, e.g. a firmware configuration read from its own file) with
    the given rows of ``section`` applied; errors name the option."""
    given = [flag for flag in flags.given() if flag.section == section]
    changes = {flag.option: (flag.field.partition(".")[2], flags.values[flag.param]) for flag in given}
    return options.override(base, changes)


def override(config: C, changes: dict[str, tuple[str, Any]], sources: list[str]) -> C:
    """``config`` with dotted fields replaced (``{"--arith": ("firmware.arith", "float")}``); a value
    the configuration refuses raises CliError naming the option that set the field."""
    nested: dict[str, dict[str, tuple[str, Any]]] = {}
    top: dict[str, tuple[str, Any]] = {}
    for option, (field, value) in changes.items():
        head, dot, leaf = field.partition(".")
        if dot:
            nested.setdefault(head, {})[option] = (leaf, value)
        else:
            top[option] = (field, value)
    for head, fields in nested.items():  # each sub-table's own checks name the option (tables in tables too)
        top[next(iter(fields))] = (head, override(getattr(config, head), fields, sources))
    try:
        return options.override(config, top, sources)
    except CliError as exc:
        raise CliError(_named(str(exc), changes)) from exc


def _named(text: str, changes: dict[str, tuple[str, Any]]) -> str:
    """An error about a dotted field (``--arith: firmware.multiplier: ...``, the first option named
    by :func:`options.override`) named by the option that set that field instead."""
    _, _, rest = text.partition(": ")
    field, _, reason = rest.partition(": ")
    for option, (dotted, _) in changes.items():
        if re.fullmatch(rf"{re.escape(dotted)}(\[\d+\])?", field):
            return f"{option}: {reason}"
    return text


def takes_scenario(
    command: str, *, scenario_option_hidden: bool = False, scenario_file: bool = True
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Give the typer command ``command`` the scenario file (``SCENARIO`` after the command's own
    arguments, or ``--scenario``; not with ``scenario_file=False``) and the rows of :data:`FLAGS`
    it takes, as options after its own; the function receives them as one keyword argument
    ``flags`` (:class:`ScenarioFlags`)."""

    def wrap(func: Callable[..., Any]) -> Callable[..., Any]:  # a function of another signature
        signature = inspect.signature(func, eval_str=True)  # typer reads the annotations as objects
        own = [p.replace(kind=_KW) for p in signature.parameters.values() if p.name != "flags"]
        mine = flags_of(command)
        scenario_arg = inspect.Parameter("scenario_file", _KW, default=None, annotation=ScenarioArg)
        scenario_opt = inspect.Parameter(
            "scenario",
            _KW,
            default=None,
            annotation=Annotated[Path | None, typer.Option(help=SCENARIO_HELP, hidden=scenario_option_hidden)],
        )
        extra = [inspect.Parameter(flag.param, _KW, default=None, annotation=flag.annotation) for flag in mine]
        clash = {p.name for p in own} & {p.name for p in (scenario_arg, scenario_opt, *extra)}
        if clash:
            raise TypeError(f"{func.__name__}: parameters {sorted(clash)} belong to the scenario flags")
        arguments = [p for p in own if _is_argument(p)]
        rest = [p for p in own if not _is_argument(p)]

        @functools.wraps(func)
        def command_with_scenario(**kwargs: Any) -> Any:
            file_arg, file_opt = kwargs.pop("scenario_file", None), kwargs.pop("scenario", None)
            values = {flag.param: kwargs.pop(flag.param) for flag in mine}
            return func(flags=ScenarioFlags.of(file_opt, file_arg, values), **kwargs)

        if scenario_file:
            parameters = [*arguments, scenario_arg, *rest, scenario_opt, *extra]
        else:
            parameters = [*arguments, *rest, *extra]
        # typer reads the command's signature with inspect, which honours __signature__ (not declared on functions)
        typed = signature.replace(parameters=parameters)
        command_with_scenario.__signature__ = typed  # type: ignore[attr-defined]  # inspect reads it, undeclared
        return command_with_scenario

    return wrap


_KW = inspect.Parameter.KEYWORD_ONLY


def _is_argument(parameter: inspect.Parameter) -> bool:
    """Whether a parameter is declared as a typer Argument (positional on the command line)."""
    metadata = getattr(parameter.annotation, "__metadata__", ())
    return any(isinstance(m, typer.models.ArgumentInfo) for m in metadata)
