"""A firmware project: the project file (``robosoc.toml``) that describes a user's firmware as data.

A project is a folder with C sources and a ``robosoc.toml``::

    [project]
    name = "pingpong"
    sources = ["tasks.c"]            # relative to the project folder
    include_dirs = ["include"]       # the project folder itself is always searched
    defines = ["LOOPS=3"]            # NAME or NAME=VALUE, for every build
    libraries = ["estimator", "pid"] # robosoc's C libraries to link (math is always linked)
    arith = ["float", "fixed"]       # the builds the project supports (real_t soft-float / Q16.16)
    multiplier = [true, false]
    main = ""                        # "": robosoc generates main() from [[tasks]]; or the source
                                     # (one of ``sources``) whose own main() creates the tasks

    [[tasks]]                        # one table per task; created in this order on their tiles
    name = "ping"                    # a C identifier: how tables and reports name the task
    label = "PING"                   # optional: how Table I prints it (default: its name)
    tile = [0, 1]
    release = "event"                # "event": a job per message on ``port``; "periodic"
    port = 1                         # event: the port whose messages release a job
    deadline_ticks = 10              # relative deadline in kernel ticks
    stack_bytes = 2048
    init = "ping_init"               # optional: called on the task's tile before the kernel starts
    on_message = "ping_on_message"   # event release: void f(const os_msg_t *msg, void *arg)
    on_period = ""                   # periodic release: void f(void *arg)
    period_ticks = 10                # periodic release: period (and capacity_ticks <= deadline)
    capacity_ticks = 10

    [[messages]]                     # what travels between tasks and the I/O tile
    name = "sensor"
    port = 1                         # the destination port
    source = "io"                    # "io" (the host's I/O tile) or a task's name
    destination = "ping"             # "io" or a task's name
    packet = "sensor"                # the format: one of robosoc's packets (robosoc_packets.h)

    [[messages]]                     # between tasks, a format of the message's own:
    name = "command"
    port = 2
    source = "ping"
    destination = "pong"
    fields = [{name = "roll_sp", type = "real"}, {name = "rates", type = "real", count = 3}]

A message to a task on its event ``port`` releases a job; on another port of the task's tile (one
no task there takes as its event port) it waits in the kernel until the task reads it with
``os_probe``/``os_recv``: how a task takes a second input (the position example's fix).

A message's format is ``packet``, one of robosoc's packets (:data:`ROBOSOC_PACKETS`), or, between
tasks, ``fields``, never both.  From ``io`` the packet is what the I/O tile sends,
:data:`IO_PACKETS` (default ``sensor``); to ``io`` the PWM commands, :data:`TO_IO_PACKETS` (the
default); between tasks any of robosoc's (``estimate``: the estimator and PID libraries') or
none.  ``fields`` are ``{name, type, count = 1}``: a C identifier each, no name twice, ``type`` one
of ``u16``, ``u32``, ``i32``, ``q16`` (Q16.16), ``f32``, ``real`` (the build's real_t, 4 bytes),
``count`` 1..58; laid out in order without padding within one NoC packet's payload (116 bytes)
by :func:`robosoc.config.packet_layout.lay_out`, which refuses a layout that would need padding,
naming the field.  The generated header has, per message with a format, ``robosoc_msg_<name>_t``
(``struct robosoc_msg_<name>`` for fields, each offset asserted) and ``ROBOSOC_MSG_<NAME>_BYTES``.

    [[telemetry]]                    # values the host reads from a task's memory (no simulated cycle)
    name = "est_height"              # the column in flight.csv and the MCAP topic's field
    task = "ping"                    # read from this task's tile between its jobs
    value = "state.alt.h"            # a variable, its members and an element: x, x.a.b, x.v[2]
    type = "real"                    # "real" (float or Q16.16 as built), "f32", "q16", "i32", "u32"

    [[reference]]                    # optional: published figures Table I prints beside the project's
    task = "ping"                    # and checks the orderings of (robosoc table)
    build = "fixed+mul"              # float+mul, float-no-mul, fixed+mul or fixed-no-mul
    response_ms = 1.5                # mean response time per job
    energy_nj = 1200.0               # mean energy per job

    [chip]                           # optional: the chip the project is made for, any chip field
    powered_off = []                 # (robosoc scenario show lists them); default: the seed's 2x2,
                                     # every core tile no task uses powered off

    [scenario]                       # optional: scenario defaults, any field but chip and
    duration_s = 29.0                # firmware.project (robosoc scenario show lists them)
    sensors.position.enabled = true

A scenario that flies the project starts from these defaults: the built-in scenario, the project's
``[chip]`` and ``[scenario]``, then the scenario file's own fields, then the command's options
(:mod:`robosoc.config.project_scenario`).

The firmware's ``main`` is generated from the task table (:mod:`robosoc.host.project_main`): on
each tile it calls the ``init`` of the tasks mapped there and creates them with the kernel, in
the order of the file.  Errors name the file and the dotted key (``tasks[1].port``).
"""

from __future__ import annotations

import dataclasses
import functools
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from robosoc.config.chip import ChipConfig
from robosoc.config.dotted import flatten
from robosoc.config.firmware import ARITH_CHOICES
from robosoc.config.packet_layout import FIELD_BYTES, FIELD_TYPES, MAX_PAYLOAD_FLITS, LayoutError, lay_out
from robosoc.config.ranges import check_fields
from robosoc.config.validate import ConfigError, from_mapping, parse_toml_text, read_toml_text
from robosoc.firmware import LIBRARIES

__all__ = [
    "BUILD_LABELS",
    "IO",
    "IO_PACKETS",
    "PROJECT_FILE",
    "ROBOSOC_PACKETS",
    "TELEMETRY_TYPES",
    "FirmwareProject",
    "MessageField",
    "MessageSpec",
    "ProjectInfo",
    "ReferenceFigure",
    "TaskSpec",
    "TelemetrySpec",
    "load_project",
]

PROJECT_FILE = "robosoc.toml"
IO = "io"
"""The name of the I/O tile (the host's side) as a message's source or destination."""
MAX_TASKS = 14
"""Tasks per tile the kernel can hold at most (TASK_IDs 2..15; 0 is the kernel, 1 the idle task:
``OS_MAX_TASKS`` in firmware/kernel/os_config.h, which a build sets when a tile has more than its
default)."""
MAX_PORT = 255
TELEMETRY_TYPES = ("real", "f32", "q16", "i32", "u32")
"""A telemetry value's C type: ``real`` is real_t (soft-float ``float`` or Q16.16 by the build)."""
_TELEMETRY_VALUE = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\.[A-Za-z_][A-Za-z0-9_]*)*)(?:\[([0-9]{1,6})\])?")
IO_PACKETS = ("sensor", "position")
"""What the I/O tile can send a project each sensor period (formats of robosoc.host.packets; a test
checks they are there): the sensor sample, and the position fix with the position setpoint."""
TO_IO_PACKETS = ("pwm",)
"""What the I/O tile takes from a project: the motor commands (the only packet the host decodes)."""
ROBOSOC_PACKETS = ("sensor", "estimate", "pwm", "position")
"""robosoc's packet formats (robosoc_packets.h, from robosoc.host.packets; a test checks the list),
which a message between tasks may carry too: the estimator and PID libraries speak ``estimate``."""

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_DEFINE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(=.*)?", re.DOTALL)
_C_KEYWORDS = frozenset(
    (
        "auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else", "enum", "extern",
        "float", "for", "goto", "if", "inline", "int", "long", "register", "restrict", "return", "short", "signed",
        "sizeof", "static", "struct", "switch", "typedef", "union", "unsigned", "void", "volatile", "while", "main",
    )
)  # fmt: skip


def _identifier(name: str, value: str, what: str) -> None:
    if not _IDENTIFIER.fullmatch(value) or value in _C_KEYWORDS:
        raise ValueError(f"{name}: must be a C identifier ({what}), got {value!r}")


@dataclass(frozen=True)
class TaskSpec:
    """One task of a project and where it runs (see the module docstring for each key)."""

    name: str
    tile: tuple[int, int]
    release: Literal["event", "periodic"] = "event"
    port: int | None = None
    deadline_ticks: int = 10
    period_ticks: int | None = None
    capacity_ticks: int | None = None
    stack_bytes: int = 2048
    init: str = ""
    on_message: str = ""
    on_period: str = ""
    label: str = ""

    def __post_init__(self) -> None:
        _identifier("name", self.name, "it names the task in C and in reports")
        if len(self.label) > 24 or not self.label.isprintable():
            raise ValueError(f"label: at most 24 printable characters, got {self.label!r}")
        if self.name == IO:
            raise ValueError(f"name: {IO!r} is the I/O tile's name")
        if len(self.tile) != 2 or min(self.tile) < 0:
            raise ValueError(f"tile: must be [x, y] with x, y >= 0, got {list(self.tile)}")
        for key in ("init", "on_message", "on_period"):
            value = getattr(self, key)
            if value:
                _identifier(key, value, "a C function of the project")
        if not 1 <= self.deadline_ticks <= 1_000_000:
            raise ValueError(f"deadline_ticks: must be between 1 and 1000000, got {self.deadline_ticks}")
        if not 256 <= self.stack_bytes <= 1 << 20 or self.stack_bytes % 16:
            raise ValueError(f"stack_bytes: must be a multiple of 16 from 256 to 1048576, got {self.stack_bytes}")
        if self.port is not None and not 1 <= self.port <= MAX_PORT:
            raise ValueError(f"port: must be between 1 and {MAX_PORT}, got {self.port}")
        if self.release == "event":
            if self.port is None:
                raise ValueError("port: an event-released task needs the port whose messages release it")
            if not self.on_message:
                raise ValueError("on_message: an event-released task needs its job function")
            for key in ("period_ticks", "capacity_ticks"):
                if getattr(self, key) is not None:
                    raise ValueError(f"{key}: only for periodic release (release = 'periodic')")
        else:
            if not self.on_period:
                raise ValueError("on_period: a periodic task needs its job function")
            if self.period_ticks is None:
                raise ValueError("period_ticks: a periodic task needs its period")
            capacity = self.capacity
            if not 1 <= capacity <= self.deadline_ticks <= self.period_ticks:
                raise ValueError(
                    "capacity_ticks: 1 <= capacity_ticks <= deadline_ticks <= period_ticks, got "
                    f"{capacity}, {self.deadline_ticks}, {self.period_ticks}"
                )

    @property
    def capacity(self) -> int:
        """Execution ticks per period (periodic release; default: the deadline)."""
        return self.capacity_ticks if self.capacity_ticks is not None else self.deadline_ticks


@dataclass(frozen=True)
class MessageField:
    """One field of a message's declared format: ``count`` values of ``type`` (a struct member)."""

    name: str
    type: str
    count: int = 1

    def __post_init__(self) -> None:
        _identifier("name", self.name, "it names the struct member")
        if self.type not in FIELD_TYPES:
            raise ValueError(f"type: must be one of {', '.join(map(repr, FIELD_TYPES))}, got {self.type!r}")
        if not 1 <= self.count <= MAX_PAYLOAD_FLITS:
            raise ValueError(f"count: must be between 1 and {MAX_PAYLOAD_FLITS}, got {self.count}")


def _quoted(names: tuple[str, ...]) -> str:
    return ", ".join(map(repr, names))


@dataclass(frozen=True)
class MessageSpec:
    """A message between two tasks, or between a task and the I/O tile, on the destination's port;
    its format is one of robosoc's packets (``packet``) or declared as ``fields`` (a C struct of
    the generated header, laid out without padding: config/packet_layout.py)."""

    name: str
    port: int
    source: str
    destination: str
    packet: str = ""
    fields: tuple[MessageField, ...] = ()

    def __post_init__(self) -> None:
        _identifier("name", self.name, "it names the message in the generated header")
        if not 1 <= self.port <= MAX_PORT:
            raise ValueError(f"port: must be between 1 and {MAX_PORT}, got {self.port}")
        if self.source == self.destination:
            raise ValueError(f"destination: the same as the source ({self.source!r})")
        if self.packet and self.fields:
            raise ValueError("fields: a message has either robosoc's packet (packet) or fields of its own, not both")
        if self.source == IO:
            if self.fields:
                sends = _quoted(IO_PACKETS)
                raise ValueError(f"fields: a message from {IO!r} is what the I/O tile sends (packet: {sends})")
            if self.packet and self.packet not in IO_PACKETS:
                raise ValueError(f"packet: the I/O tile sends {_quoted(IO_PACKETS)}, got {self.packet!r}")
        elif self.destination == IO:
            if self.fields:
                raise ValueError(f"fields: the I/O tile takes {_quoted(TO_IO_PACKETS)} packets only (packet)")
            if self.packet and self.packet not in TO_IO_PACKETS:
                raise ValueError(f"packet: the I/O tile takes {_quoted(TO_IO_PACKETS)}, got {self.packet!r}")
        elif self.packet and self.packet not in ROBOSOC_PACKETS:
            raise ValueError(
                f"packet: between tasks one of robosoc's packets ({_quoted(ROBOSOC_PACKETS)}), got {self.packet!r}; "
                "or declare the message's own fields"
            )
        members: dict[str, int] = {}
        for i, f in enumerate(self.fields):
            if f.name in members:
                raise ValueError(f"fields[{i}].name: {f.name!r} is also fields[{members[f.name]}]")
            members[f.name] = i
        try:
            lay_out([(f.name, f.type, f.count) for f in self.fields])
        except LayoutError as exc:
            raise ValueError(f"fields{'' if exc.index is None else f'[{exc.index}]'}: {exc.reason}") from None

    @property
    def io_packet(self) -> str:
        """What the I/O tile sends in a message from it (``packet``, by default the sensor packet)."""
        return self.packet or IO_PACKETS[0]

    @property
    def robosoc_packet(self) -> str:
        """The robosoc packet the message carries: ``packet``; from the I/O tile by default the
        sensor packet, to it the PWM packet; "" for a message with ``fields`` or no format declared."""
        if self.source == IO:
            return self.io_packet
        if self.destination == IO:
            return self.packet or TO_IO_PACKETS[0]
        return self.packet

    @property
    def offsets(self) -> tuple[int, ...]:
        """The byte offset of each of ``fields`` in the message."""
        return lay_out([(f.name, f.type, f.count) for f in self.fields])

    @property
    def size(self) -> int:
        """Bytes of a message with ``fields`` (0 without)."""
        return sum(FIELD_BYTES[f.type] * f.count for f in self.fields)


@dataclass(frozen=True)
class TelemetrySpec:
    """A named value a task publishes to the logs: read by the host from the task's memory at the
    close of each sensor period (a host read: it costs the chip no cycle)."""

    name: str
    task: str
    value: str
    type: str = "real"

    def __post_init__(self) -> None:
        _identifier("name", self.name, "it names a column of flight.csv")
        match = _TELEMETRY_VALUE.fullmatch(self.value)
        if match is None:
            raise ValueError(f"value: a variable, then .member parts and one optional [index], got {self.value!r}")
        if self.type not in TELEMETRY_TYPES:
            raise ValueError(f"type: must be one of {', '.join(map(repr, TELEMETRY_TYPES))}, got {self.type!r}")

    @property
    def variable(self) -> str:
        """The C variable (a global or file-scope static of the project's sources)."""
        return self.value.split(".", 1)[0].split("[", 1)[0]

    @property
    def member(self) -> str:
        """The dotted member path inside the variable ("" for the variable itself)."""
        match = _TELEMETRY_VALUE.fullmatch(self.value)
        assert match is not None  # checked in __post_init__
        return match.group(2)[1:]

    @property
    def index(self) -> int:
        """The element of an array member (0 when no index is given)."""
        match = _TELEMETRY_VALUE.fullmatch(self.value)
        assert match is not None
        return int(match.group(3) or 0)


BUILD_LABELS = tuple(f"{a}{'+mul' if m else '-no-mul'}" for a in ARITH_CHOICES for m in (True, False))
"""The four builds as tables name them (:attr:`robosoc.config.firmware.FirmwareConfig.label`)."""


@dataclass(frozen=True)
class ReferenceFigure:
    """A published figure of one task in one build (e.g. the seed paper's Table I) that
    ``robosoc table`` prints beside the measured one and checks the build orderings against."""

    task: str
    build: str
    response_ms: float
    energy_nj: float

    def __post_init__(self) -> None:
        if self.build not in BUILD_LABELS:
            raise ValueError(f"build: one of {', '.join(BUILD_LABELS)}, got {self.build!r}")
        check_fields(self)  # both figures in their ranges (config/ranges.py)


@dataclass(frozen=True)
class ProjectInfo:
    """The ``[project]`` table: name, sources and the builds the project supports."""

    name: str = "project"
    sources: tuple[str, ...] = ()
    include_dirs: tuple[str, ...] = ()
    defines: tuple[str, ...] = ()
    libraries: tuple[str, ...] = ()
    arith: tuple[str, ...] = ARITH_CHOICES
    multiplier: tuple[bool, ...] = (True, False)
    main: str = ""

    def __post_init__(self) -> None:
        if not self.name or not re.fullmatch(r"[A-Za-z0-9_.-]+", self.name):
            raise ValueError(f"name: letters, digits, '_', '-' or '.', got {self.name!r}")
        if not self.sources:
            raise ValueError("sources: a project needs at least one C or assembly source")
        for i, source in enumerate(self.sources):
            if Path(source).suffix not in (".c", ".S", ".s"):
                raise ValueError(f"sources[{i}]: expected a .c, .S or .s file, got {source!r}")
        for i, define in enumerate(self.defines):
            if not _DEFINE.fullmatch(define):
                raise ValueError(f"defines[{i}]: expected NAME or NAME=VALUE, got {define!r}")
        for i, library in enumerate(self.libraries):
            if library not in LIBRARIES:
                raise ValueError(f"libraries[{i}]: no library {library!r} (robosoc ships {', '.join(LIBRARIES)})")
        if not self.arith or any(a not in ARITH_CHOICES for a in self.arith):
            raise ValueError(f"arith: each one of {', '.join(map(repr, ARITH_CHOICES))}, got {list(self.arith)}")
        if not self.multiplier:
            raise ValueError("multiplier: at least one of true, false")
        if self.main and self.main not in self.sources:
            raise ValueError(f"main: must be one of the sources (the file that defines main()), got {self.main!r}")


@dataclass(frozen=True)
class FirmwareProject:
    """A whole project file, checked as a whole (tasks, ports, messages); ``folder`` is where its
    relative paths start."""

    project: ProjectInfo = field(default_factory=ProjectInfo)
    tasks: tuple[TaskSpec, ...] = ()
    messages: tuple[MessageSpec, ...] = ()
    telemetry: tuple[TelemetrySpec, ...] = ()
    reference: tuple[ReferenceFigure, ...] = ()
    folder: str = "."
    chip: tuple[tuple[str, Any], ...] = field(default=(), hash=False)
    """The ``[chip]`` table as dotted fields (checked when loaded; applied by
    :meth:`robosoc.config.firmware.FirmwareConfig.project_chip`)."""
    scenario: tuple[tuple[str, Any], ...] = field(default=(), hash=False)
    """The ``[scenario]`` table as dotted fields: defaults of a scenario that flies the project."""

    def __post_init__(self) -> None:
        if not self.tasks:
            raise ValueError("tasks: a project needs at least one task ([[tasks]] tables)")
        names: dict[str, int] = {}
        for i, task in enumerate(self.tasks):
            if task.name in names:
                raise ValueError(f"tasks[{i}].name: {task.name!r} is also tasks[{names[task.name]}]")
            names[task.name] = i
        ports: dict[tuple[tuple[int, int], int], int] = {}
        per_tile: dict[tuple[int, int], int] = {}
        for i, task in enumerate(self.tasks):
            tile = (*task.tile,)  # a tuple even if given a list (as tuple(), keeping the pair type)
            per_tile[tile] = per_tile.get(tile, 0) + 1
            if per_tile[tile] > MAX_TASKS:
                raise ValueError(f"tasks[{i}].tile: more than {MAX_TASKS} tasks on tile {list(tile)}")
            if task.port is None:
                continue
            key = (tile, task.port)
            if key in ports:
                other = self.tasks[ports[key]].name
                raise ValueError(f"tasks[{i}].port: port {task.port} of tile {list(tile)} is taken by task {other!r}")
            ports[key] = i
        seen: dict[str, int] = {}
        for i, message in enumerate(self.messages):
            if message.name in seen:
                raise ValueError(f"messages[{i}].name: {message.name!r} is also messages[{seen[message.name]}]")
            seen[message.name] = i
            for which in ("source", "destination"):
                end = getattr(message, which)
                if end != IO and end not in names:
                    raise ValueError(f"messages[{i}].{which}: no task {end!r} (tasks: {', '.join(names)}, or {IO!r})")
            if message.destination != IO:
                task = self.tasks[names[message.destination]]
                owner = ports.get(((*task.tile,), message.port))
                if owner is not None and self.tasks[owner].name != task.name:
                    raise ValueError(
                        f"messages[{i}].port: port {message.port} of tile {list(task.tile)} releases task "
                        f"{self.tasks[owner].name!r}, not {message.destination!r} (its event port is {task.port})"
                    )

        published: dict[str, int] = {}
        for i, value in enumerate(self.telemetry):
            if value.name in published:
                raise ValueError(f"telemetry[{i}].name: {value.name!r} is also telemetry[{published[value.name]}]")
            published[value.name] = i
            if value.task not in names:
                raise ValueError(f"telemetry[{i}].task: no task {value.task!r} (tasks: {', '.join(names)})")
        figures: dict[tuple[str, str], int] = {}
        for i, figure in enumerate(self.reference):
            if figure.task not in names:
                raise ValueError(f"reference[{i}].task: no task {figure.task!r} (tasks: {', '.join(names)})")
            pair = (figure.task, figure.build)
            if pair in figures:
                raise ValueError(f"reference[{i}]: {figure.task} {figure.build} is also reference[{figures[pair]}]")
            figures[pair] = i

    @property
    def file(self) -> Path:
        """The project file."""
        return Path(self.folder) / PROJECT_FILE

    @property
    def task_names(self) -> tuple[str, ...]:
        return tuple(task.name for task in self.tasks)

    def label(self, name: str) -> str:
        """How Table I prints task ``name``: its ``label``, or its name."""
        return next((t.label for t in self.tasks if t.name == name and t.label), name)

    def task(self, name: str) -> TaskSpec:
        """The task called ``name``.

        Raises:
            KeyError: no such task.
        """
        for task in self.tasks:
            if task.name == name:
                return task
        raise KeyError(name)

    def tiles(self, mapping: Mapping[str, tuple[int, int]] | None = None) -> list[tuple[int, int]]:
        """The tiles that run a task (with ``mapping`` moving some), in the order of their first task."""
        out: list[tuple[int, int]] = []
        for task in self.tasks:
            tile = tuple((mapping or {}).get(task.name, task.tile))
            tile = (int(tile[0]), int(tile[1]))
            if tile not in out:
                out.append(tile)
        return out

    def inputs(self) -> list[MessageSpec]:
        """The messages the I/O tile sends (what the host feeds the firmware; ``packet`` says which)."""
        return [m for m in self.messages if m.source == IO]

    def outputs(self) -> list[MessageSpec]:
        """The messages the firmware sends to the I/O tile (actuator commands, telemetry)."""
        return [m for m in self.messages if m.destination == IO]

    def path(self, relative: str) -> Path:
        """A path of the project file, relative to the project folder."""
        return Path(self.folder) / relative

    def check_build(self, arith: str, multiplier: bool) -> None:
        """Raise ValueError unless the project supports this build (its ``[project]`` lists)."""
        info = self.project
        if arith not in info.arith:
            raise ValueError(f"arith: the project {info.name!r} supports {', '.join(info.arith)}, not {arith!r}")
        if multiplier not in info.multiplier:
            with_or_not = "with" if multiplier else "without"
            raise ValueError(f"multiplier: the project {info.name!r} has no build {with_or_not} the multiplier")

    def check_chip(self, chip: ChipConfig, mapping: Mapping[str, tuple[int, int]] | None = None) -> None:
        """Raise ValueError unless every task's tile (``mapping`` moving some) is a powered core
        tile of ``chip``."""
        for i, task in enumerate(self.tasks):
            xy = (mapping or {}).get(task.name, (int(task.tile[0]), int(task.tile[1])))
            problem = chip.core_tile_problem(xy)
            if problem:
                raise ValueError(f"tasks[{i}].tile: {list(xy)} ({task.name}) {problem}")


def load_project(folder: str | Path) -> FirmwareProject:
    """The project in ``folder`` (its ``robosoc.toml``), or the project file itself.

    Raises:
        ConfigError: naming the file and the key: a missing file, unknown keys, wrong types, values
            out of range, two tasks on one port, a message to no task, a source that is not there,
            a ``[chip]`` or ``[scenario]`` field that is no field of its table.
    """
    path = Path(folder)
    if path.is_dir():
        path = path / PROJECT_FILE
    text = read_toml_text(path, "project file")
    project = _project_of_text(str(path), text)
    for i, source in enumerate(project.project.sources):
        if not project.path(source).is_file():
            raise ConfigError(str(path), f"project.sources[{i}]", f"no such file: {project.path(source)}")
    for i, include in enumerate(project.project.include_dirs):
        if not project.path(include).is_dir():
            raise ConfigError(str(path), f"project.include_dirs[{i}]", f"no such folder: {project.path(include)}")
    return project


@functools.lru_cache(maxsize=32)
def _project_of_text(file: str, text: str) -> FirmwareProject:
    """The checked project of the file ``file`` holding ``text``; kept, since one flight reads its
    project several times (the build, the image, the telemetry, the summary) and the text decides."""
    path = Path(file)
    data = parse_toml_text(text, path)
    if "folder" in data:
        raise ConfigError(str(path), "folder", "unknown field (the project's folder is where its file is)")
    chip = _defaults_table(data.pop("chip", {}), path, "chip")
    scenario = _defaults_table(data.pop("scenario", {}), path, "scenario")
    data["folder"] = str(path.parent)
    project = from_mapping(FirmwareProject, data, str(path))
    return dataclasses.replace(project, chip=chip, scenario=scenario)


def _defaults_table(table: Any, path: Path, name: str) -> tuple[tuple[str, Any], ...]:
    """The project's ``[chip]`` or ``[scenario]`` table as dotted fields, each name checked
    (values are checked with the scenario that flies the project: they may need its other fields)."""
    from robosoc.config.scenario_fields import check_field  # the scenario's fields (config.scenario names projects)

    if not isinstance(table, dict):
        raise ConfigError(str(path), name, f"expected a table of {name} fields, got {table!r}")
    flat = flatten(table)
    for key in flat:
        dotted = f"{name}.{key}"
        if name == "scenario" and key.split(".", 1)[0] == "chip":
            raise ConfigError(str(path), dotted, "the chip's fields go in the project's [chip] table")
        if name == "scenario" and key == "firmware.project":
            raise ConfigError(str(path), dotted, "a project file does not name a project (it is one)")
        check_field(key if name == "scenario" else dotted, str(path), dotted)
    return tuple(flat.items())
