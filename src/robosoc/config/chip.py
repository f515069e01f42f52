"""Platform configuration of the MPSoC: mesh size, I/O tile, powered-off tiles, per-tile options, NoC.

Everything is a frozen dataclass checked in ``__post_init__`` (errors are ``ValueError("field: reason")``)
and loadable from TOML through :func:`load_chip_config`, whose errors name the file and the dotted field::

    width = 4
    height = 4
    io_tile = [0, 0]
    powered_off = [[3, 3]]

    [tile]                 # defaults for every tile
    clock_period_ns = 4.0

    [[tiles]]              # per-tile overrides
    x = 1
    y = 2
    multiplier = false

    [noc]
    buffer_depth = 16
    arbiter = "hermes"      # or "per-output" (idealised router)
    clock_gating = false    # true: idle routers stop their clock (gate_after_cycles, wake_cycles)

Coordinates are ``(x, y)`` with ``0 <= x < width`` and ``0 <= y < height``; ``y`` grows northwards. The
NoC address of a tile is ``(x << 4) | y`` (ORCA packet format), hence at most 16 tiles per side.

Router model (docs/noc.md): ``noc.arbiter = "hermes"`` (the default) is the ORCA Hermes router as measured
on its RTL (platform.md §4): one switch-control state machine per router, an uncontended header costing
5 cycles per router (:data:`HERMES_ROUTING_LATENCY` = 4 cycles at the head of the buffer, the crossing in
the 5th) and body flits following at 1 flit per cycle. ``"per-output"`` is an idealised router with one
round-robin arbiter per output port and a configurable routing latency, for comparing router designs.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, get_args

from robosoc.config.ranges import CLOCK_PERIOD_NS, MAX_CHIP_SRAM_BYTES, check_fields, format_bytes
from robosoc.config.validate import load_toml

__all__ = [
    "ARBITERS",
    "HERMES_ROUTING_LATENCY",
    "MAX_CLOCK_DIVIDER",
    "MIN_PACKET_FLITS",
    "ChipConfig",
    "DvfsConfig",
    "NocConfig",
    "TileConfig",
    "TileOverride",
    "load_chip_config",
]

#: Router models: the Hermes RTL's single switch controller, or one idealised arbiter per output port.
Arbiter = Literal["hermes", "per-output"]
ARBITERS: tuple[Arbiter, ...] = get_args(Arbiter)
#: Cycles an uncontended header spends at the head of an input buffer before it crosses (in the next
#: cycle) on the Hermes RTL: 5 cycles per router, measured (platform.md §4, docs/noc.md).
HERMES_ROUTING_LATENCY = 4
#: Size of the NI send and receive memories in flits (128 bytes of 16-bit flits, ORCA).
NI_MEMORY_FLITS = 64
#: Shortest packet: destination, size and one payload flit. On the Hermes RTL a packet of size 0
#: (2 flits) keeps its connection open and swallows the next packet (platform.md §4).
MIN_PACKET_FLITS = 3
MAX_MESH_SIDE = 16
#: The slowest core clock a tile may have, as a divider of the chip's (NoC) clock.
MAX_CLOCK_DIVIDER = 64
#: How the cores treat the HF-RISCV RTL's errata (see ``ChipConfig.errata``).
ERRATA_CHOICES = ("spec", "rtl")
ENGINE_CHOICES = ("interp", "jit", "auto")
"""How the cores execute: the interpreter, or code translated at a region's first arrival or once
it turns hot (docs/translation.md); every engine gives the same cycles, counters and outputs."""


def engine_name(value: str, what: str = "engine", quote: bool = True) -> str:
    """``value`` if it names an engine (:data:`ENGINE_CHOICES`): the one check of an engine's name
    (the configuration's field, the command line's ``--engine``, the chips' and the benchmarks'
    arguments, through :func:`robosoc.chip.engines.resolve_engine`).

    Raises:
        ValueError: naming ``what`` and the choices (quoted, as the configuration's messages are;
            bare with ``quote`` False, as the command line's are).
    """
    if value not in ENGINE_CHOICES:
        choices = ", ".join(map(repr, ENGINE_CHOICES)) if quote else ", ".join(ENGINE_CHOICES)
        raise ValueError(f"{what}: must be one of {choices}, got {value!r}")
    return value


DEFAULT_ENGINE = "auto"
"""The engine of one core when none is named: interprets, and translates what turns hot."""
DEFAULT_CHIP_ENGINE = "auto"
"""The engine of a chip's cores when none is named: as on one core (on the flights' chips it flies
1.1 to 1.25x faster than the interpreter over 10 s, the suite's chip tests take no longer;
docs/translation.md)."""


def _check_sram(name: str, value: int) -> None:
    if value % 4 != 0 or not 4096 <= value <= 1 << 30:
        raise ValueError(f"{name}: must be a multiple of 4 between 4096 and 2**30 bytes, got {value}")


def _check_period(name: str, value: float) -> None:
    CLOCK_PERIOD_NS.check(name, value)


@dataclass(frozen=True)
class TileConfig:
    """Options of one tile (the defaults apply to every tile not overridden).

    Attributes:
        multiplier: the core has the hardware multiplier (M extension subset of HF-RISCV).
        sram_bytes: size of the tile's SRAM (2 MiB in the paper).
        clock_period_ns: core clock period (4 ns = 250 MHz).
    """

    multiplier: bool = True
    sram_bytes: int = 2 * 1024 * 1024
    clock_period_ns: float = 4.0

    def __post_init__(self) -> None:
        _check_sram("sram_bytes", self.sram_bytes)
        _check_period("clock_period_ns", self.clock_period_ns)


@dataclass(frozen=True)
class TileOverride:
    """Per-tile override: fields left at ``None`` keep the chip-wide :class:`TileConfig` value.

    ``clock_period_ns`` gives the tile's core its own clock: a whole multiple d (1..64) of the chip's
    clock ``tile.clock_period_ns``, which stays the NoC's, the network interface's and every cycle
    count's (the core executes one of its cycles every d chip cycles; docs/power.md, "Per-tile clock").
    """

    x: int
    y: int
    multiplier: bool | None = None
    sram_bytes: int | None = None
    clock_period_ns: float | None = None

    def __post_init__(self) -> None:
        if self.x < 0:
            raise ValueError(f"x: must be >= 0, got {self.x}")
        if self.y < 0:
            raise ValueError(f"y: must be >= 0, got {self.y}")
        if self.sram_bytes is not None:
            _check_sram("sram_bytes", self.sram_bytes)
        if self.clock_period_ns is not None:
            _check_period("clock_period_ns", self.clock_period_ns)


@dataclass(frozen=True)
class NocConfig:
    """Hermes router and packet parameters.

    Attributes:
        buffer_depth: flits per router input buffer: 16 as in the seed's paper (the ORCA repository's
            RTL uses 4). At least 2: with one-slot buffers and a one-cycle credit loop a connection
            moves only one flit every 2 cycles.
        flit_bits: flit width; the ORCA packet format uses 16-bit flits.
        max_packet_flits: longest packet including the destination and size flits; at most the
            64-flit NI memories.
        routing_latency: cycles an uncontended header waits at the head of an input buffer before it
            crosses (the per-router header cost is ``routing_latency + 1``). Fixed at
            :data:`HERMES_ROUTING_LATENCY` by the Hermes switch controller; free with ``"per-output"``.
        arbiter: ``"hermes"``, the RTL's single switch controller per router (default), or
            ``"per-output"``, an idealised router with one round-robin arbiter per output port.
        clock_gating: a router that has held no flit for ``gate_after_cycles`` cycles stops its
            clock (it then costs only its leakage) until a flit arrives; the flit's router restarts
            ``wake_cycles`` later, delaying every decision of that router by as much (docs/noc.md,
            "Clock gating"; docs/power.md).  Off by default: the routers' clocks always run.
        gate_after_cycles: idle cycles before a router's clock stops (assumed: 8; at least 1).
        wake_cycles: cycles a stopped router needs before it acts on the flit that woke it
            (assumed: 2, detecting the flit and re-enabling the clock-gating cell).
        power_off_unused_routers: the router of a powered-off tile that no XY route between two
            powered tiles crosses is switched off too (no energy at all, leakage included); by
            default a powered-off tile keeps its router (:meth:`ChipConfig.routers_off`).
    """

    buffer_depth: int = 16
    flit_bits: int = 16
    max_packet_flits: int = NI_MEMORY_FLITS
    routing_latency: int = HERMES_ROUTING_LATENCY
    arbiter: Arbiter = "hermes"
    clock_gating: bool = False
    gate_after_cycles: int = 8
    wake_cycles: int = 2
    power_off_unused_routers: bool = False

    def __post_init__(self) -> None:
        if not 2 <= self.buffer_depth <= 256:
            raise ValueError(f"buffer_depth: must be between 2 and 256 flits, got {self.buffer_depth}")
        if self.flit_bits not in (16, 32):
            raise ValueError(f"flit_bits: must be 16 (ORCA) or 32, got {self.flit_bits}")
        if not MIN_PACKET_FLITS <= self.max_packet_flits <= NI_MEMORY_FLITS:
            raise ValueError(
                f"max_packet_flits: must be between {MIN_PACKET_FLITS} and {NI_MEMORY_FLITS} (the NI memories), "
                f"got {self.max_packet_flits}"
            )
        if self.arbiter not in ARBITERS:
            raise ValueError(f"arbiter: must be one of {', '.join(map(repr, ARBITERS))}, got {self.arbiter!r}")
        if not 0 <= self.routing_latency <= 64:
            raise ValueError(f"routing_latency: must be between 0 and 64 cycles, got {self.routing_latency}")
        if not 1 <= self.gate_after_cycles <= 1_000_000:
            raise ValueError(f"gate_after_cycles: must be between 1 and 1000000 cycles, got {self.gate_after_cycles}")
        if not 0 <= self.wake_cycles <= 1000:
            raise ValueError(f"wake_cycles: must be between 0 and 1000 cycles, got {self.wake_cycles}")
        if self.arbiter == "hermes" and self.routing_latency != HERMES_ROUTING_LATENCY:
            raise ValueError(
                f"routing_latency: the Hermes switch controller fixes it at {HERMES_ROUTING_LATENCY} "
                f'(5 cycles per router), got {self.routing_latency}; use arbiter = "per-output" to vary it'
            )

    @property
    def gate_after(self) -> int:
        """The NoC kernel's clock-gating threshold: ``gate_after_cycles``, or -1 without clock gating."""
        return self.gate_after_cycles if self.clock_gating else -1


@dataclass(frozen=True)
class DvfsConfig:
    """The chip's voltage/frequency operating points (docs/power.md, "DVFS").

    The chip's clock (``tile.clock_period_ns``, the NoC's) and each tile's own (a ``tiles`` override's
    ``clock_period_ns``, a whole multiple of it); with ``points`` given each runs at the voltage of
    the slowest point at least as fast as its clock, and the energy coefficients, characterised at
    ``reference_v`` and the energy file's clock, are scaled: every switching energy (instructions,
    stalls, DMA, the routers' buffers and control) by ``(V/reference_v)²``, the leakage per cycle (a
    sleeping core's cycle, a router's leakage) by ``(V/reference_v)·(period/reference period)``.

    Attributes:
        points: ``[MHz, V]`` pairs, the voltage not falling as the frequency rises; empty (the
            default): no scaling, the coefficients as characterised.
        reference_v: the supply voltage of the coefficients' characterisation (assumed 1.0 V: ORCA
            does not publish it).
    """

    points: tuple[tuple[float, float], ...] = ()
    reference_v: float = 1.0

    def __post_init__(self) -> None:
        for i, (mhz, volts) in enumerate(self.points):
            if not (math.isfinite(mhz) and 1.0 <= mhz <= 2000.0):
                raise ValueError(f"points[{i}]: a frequency in 1..2000 MHz, got {mhz}")
            if not (math.isfinite(volts) and 0.1 <= volts <= 5.0):
                raise ValueError(f"points[{i}]: a voltage in 0.1..5 V, got {volts}")
        ordered = sorted(self.points)
        for (f0, v0), (f1, v1) in itertools.pairwise(ordered):
            if f0 == f1:
                raise ValueError(f"points: {f0:g} MHz is listed twice")
            if v1 < v0:
                raise ValueError(
                    f"points: {f1:g} MHz at {v1:g} V is faster than {f0:g} MHz at {v0:g} V on less voltage"
                )
        check_fields(self)  # reference_v in its range (config/ranges.py)

    def voltage_at(self, clock_period_ns: float) -> float | None:
        """The voltage the chip runs at with this clock: that of the slowest point at least as fast
        (None without points, or when the clock is faster than every point)."""
        mhz = 1000.0 / clock_period_ns
        for f, volts in sorted(self.points):
            if f >= mhz * (1 - 1e-12):
                return volts
        return None


@dataclass(frozen=True)
class ChipConfig:
    """The whole MPSoC: a ``width`` × ``height`` mesh of tiles.

    Attributes:
        width: tiles along x (1..16).
        height: tiles along y (1..16).
        io_tile: the tile bridging the NoC to the outside world (no core).
        powered_off: tiles whose core, memory and network interface are off. Their router keeps
            forwarding transit traffic (XY routes would otherwise be cut); a packet addressed to them
            is an error.
        tile: defaults for every tile.
        tiles: per-tile overrides.
        noc: router and packet parameters.
        errata: ``"spec"`` (RISC-V results; each HF-RISCV RTL erratum a program would hit is reported)
            or ``"rtl"`` (reproduce the RTL: MULHSU as MULHU, an interrupt during a multiply as in
            platform.md §3), for every core.
        engine: how the simulator executes the cores' code (:data:`ENGINE_CHOICES`): a matter of
            host speed only, never of the results.
        dvfs: the voltage/frequency points the clock's voltage is read from (energy scaling).
    """

    width: int = 2
    height: int = 2
    io_tile: tuple[int, int] = (0, 0)
    powered_off: tuple[tuple[int, int], ...] = ()
    tile: TileConfig = field(default_factory=TileConfig)
    tiles: tuple[TileOverride, ...] = ()
    noc: NocConfig = field(default_factory=NocConfig)
    errata: str = "spec"
    engine: str = DEFAULT_CHIP_ENGINE
    dvfs: DvfsConfig = field(default_factory=DvfsConfig)

    def __post_init__(self) -> None:
        if self.errata not in ERRATA_CHOICES:
            raise ValueError(f"errata: must be one of {', '.join(map(repr, ERRATA_CHOICES))}, got {self.errata!r}")
        engine_name(self.engine)
        for name in ("width", "height"):
            value = getattr(self, name)
            if not 1 <= value <= MAX_MESH_SIDE:
                raise ValueError(f"{name}: must be between 1 and {MAX_MESH_SIDE}, got {value}")
        if self.width * self.height < 2:
            raise ValueError("width: a mesh needs at least 2 tiles")
        if not self.contains(self.io_tile):
            raise ValueError(f"io_tile: {self.io_tile} is outside the {self.width}x{self.height} mesh")
        seen: set[tuple[int, int]] = set()
        for i, xy in enumerate(self.powered_off):
            if not self.contains(xy):
                raise ValueError(f"powered_off[{i}]: {xy} is outside the {self.width}x{self.height} mesh")
            if xy in seen:
                raise ValueError(f"powered_off[{i}]: {xy} is listed twice")
            if xy == self.io_tile:
                raise ValueError(f"powered_off[{i}]: {xy} is the I/O tile")
            seen.add(xy)
        overridden: set[tuple[int, int]] = set()
        for i, over in enumerate(self.tiles):
            xy = (over.x, over.y)
            if not self.contains(xy):
                raise ValueError(f"tiles[{i}]: {xy} is outside the {self.width}x{self.height} mesh")
            if xy in overridden:
                raise ValueError(f"tiles[{i}]: {xy} is overridden twice")
            overridden.add(xy)
        self._check_sram_total()
        for i, over in enumerate(self.tiles):
            if over.clock_period_ns is not None:
                self._check_divider(f"tiles[{i}].clock_period_ns", over.clock_period_ns)
        if self.dvfs.points:
            for i, over in enumerate(self.tiles):
                if over.clock_period_ns is not None:
                    self._check_point(f"tiles[{i}].clock_period_ns", over.clock_period_ns)
            self._check_point("tile.clock_period_ns", self.tile.clock_period_ns)

    def _check_divider(self, name: str, period_ns: float) -> None:
        """A tile's core clock is the chip's divided by a whole number (the NoC keeps the chip's)."""
        chip = self.tile.clock_period_ns
        ratio = period_ns / chip
        d = round(ratio)
        if d < 1 or abs(ratio - d) > 1e-9 * ratio:
            raise ValueError(
                f"{name}: {period_ns:g} ns is not a whole multiple of the chip's clock (tile.clock_period_ns = "
                f"{chip:g} ns, the NoC's): a tile's core runs at the chip's clock divided by 1..{MAX_CLOCK_DIVIDER}"
            )
        if d > MAX_CLOCK_DIVIDER:
            raise ValueError(
                f"{name}: {period_ns:g} ns is the chip's clock ({chip:g} ns) divided by {d}, more than "
                f"{MAX_CLOCK_DIVIDER}"
            )

    def tile_divider(self, xy: tuple[int, int]) -> int:
        """How many chip (NoC) cycles one core cycle of tile ``xy`` lasts: 1 unless its override
        gives it a slower clock (docs/power.md, "Per-tile clock")."""
        return round(self.tile_config(xy).clock_period_ns / self.tile.clock_period_ns)

    def tile_volts(self, xy: tuple[int, int]) -> float | None:
        """The supply voltage of tile ``xy``'s core at its clock (None without DVFS points)."""
        return self.dvfs.voltage_at(self.tile_config(xy).clock_period_ns)

    def _check_point(self, name: str, period_ns: float) -> None:
        """A clock faster than every DVFS point has no voltage to run at."""
        if self.dvfs.voltage_at(period_ns) is None:
            fastest = max(f for f, _ in self.dvfs.points)
            raise ValueError(
                f"{name}: {period_ns:g} ns ({1000 / period_ns:g} MHz) is faster than the highest DVFS point "
                f"(dvfs.points: {fastest:g} MHz)"
            )

    def _check_sram_total(self) -> None:
        """The simulator holds every tile's SRAM at the largest tile's size: refuse a chip whose total
        is beyond :data:`MAX_CHIP_SRAM_BYTES` before anything is allocated."""
        largest, field = self.tile.sram_bytes, "tile.sram_bytes"
        for i, over in enumerate(self.tiles):
            if over.sram_bytes is not None and over.sram_bytes > largest:
                largest, field = over.sram_bytes, f"tiles[{i}].sram_bytes"
        total = self.n_tiles * largest
        if total > MAX_CHIP_SRAM_BYTES:
            raise ValueError(
                f"{field}: {self.n_tiles} tiles x {format_bytes(largest)} of SRAM = {format_bytes(total)} to simulate, "
                f"more than {format_bytes(MAX_CHIP_SRAM_BYTES)} (every tile gets the largest tile's SRAM)"
            )

    def routers_off(self) -> tuple[tuple[int, int], ...]:
        """The routers switched off with ``noc.power_off_unused_routers``: those of powered-off tiles
        on no XY route between two powered tiles (the I/O tile included), so no packet can reach
        them and the timing of every packet is as with them on.  Empty without the option."""
        if not self.noc.power_off_unused_routers:
            return ()
        powered = [xy for xy in (self.tile_xy(t) for t in range(self.n_tiles)) if self.is_powered(xy)]
        used: set[tuple[int, int]] = set()
        for sx, sy in powered:
            for dx, dy in powered:
                step = 1 if dx >= sx else -1
                used.update((x, sy) for x in range(sx, dx + step, step))
                step = 1 if dy >= sy else -1
                used.update((dx, y) for y in range(sy, dy + step, step))
        return tuple(xy for xy in self.powered_off if tuple(xy) not in used)

    @property
    def n_tiles(self) -> int:
        """Number of tiles, powered or not."""
        return self.width * self.height

    def contains(self, xy: tuple[int, int]) -> bool:
        """Whether ``xy`` is a tile of the mesh."""
        x, y = xy
        return 0 <= x < self.width and 0 <= y < self.height

    def tile_index(self, xy: tuple[int, int]) -> int:
        """Row-major tile index ``y * width + x`` used by the kernels."""
        if not self.contains(xy):
            raise ValueError(f"tile {xy} is outside the {self.width}x{self.height} mesh")
        return xy[1] * self.width + xy[0]

    def tile_xy(self, index: int) -> tuple[int, int]:
        """Inverse of :meth:`tile_index`."""
        return index % self.width, index // self.width

    def is_powered(self, xy: tuple[int, int]) -> bool:
        """Whether the tile's core, memory and NI are on."""
        return tuple(xy) not in set(self.powered_off)

    def core_tile_problem(self, xy: tuple[int, int]) -> str | None:
        """Why no task can run on tile ``xy`` (outside the mesh, the I/O tile, powered off), or None."""
        if not self.contains(xy):
            return f"is outside the {self.width}x{self.height} mesh"
        if tuple(xy) == tuple(self.io_tile):
            return "is the I/O tile, which has no core"
        if not self.is_powered(xy):
            return "is powered off in the chip configuration"
        return None

    def tile_config(self, xy: tuple[int, int]) -> TileConfig:
        """The effective options of tile ``xy`` (chip defaults with its override applied)."""
        base = self.tile
        for over in self.tiles:
            if (over.x, over.y) == tuple(xy):
                changes = {
                    name: getattr(over, name)
                    for name in ("multiplier", "sram_bytes", "clock_period_ns")
                    if getattr(over, name) is not None
                }
                return dataclasses.replace(base, **changes)
        return base


def load_chip_config(path: str | Path, section: str | None = None) -> ChipConfig:
    """Read a :class:`ChipConfig` from TOML (optionally from one top-level table).

    Raises:
        robosoc.config.ConfigError: naming the file and the dotted field.
    """
    return load_toml(ChipConfig, path, section)
