"""``robosoc bench fly --breakdown``: where a chip flight's host time goes, per cause.

One lockstep flight of the firmware on the chip (:func:`robosoc.cosim.lockstep.fly_lockstep`),
timed as a whole from outside (``total_s``, as ``fly_chip`` times it) and, for the same flight, in
parts that exclude each other:

* the Python of the flight, per function: the physics step, the sensors, the flight rows, the
  sample's way to the chip, the period close (counters, job records, estimate), the commands'
  hand-out, the messages from the chip, the chip step's own Python, translation upkeep, the
  flight's end, and what is left of the lockstep loop itself.  Each is the time spent in that
  function minus the time spent in the others called from it (a stack of sections, read with
  ``time.perf_counter`` at every entry and exit, so they add up to the flight's time);
* the chip loop (:func:`robosoc.kernels.chip.run_chip`), split by the loop itself with the host's
  cycle counter (``G_PROF``: interpreter, dispatch loop with translated code, network-interface
  accesses, waking cores, the NoC, the translated blocks' counts, the rest: planning quanta and
  handling stops), the counter's ticks turned into seconds with its rate over the flight; what
  the section measured beyond the loop's own ticks is the cost of calling it (numba's argument
  unboxing and dispatch).

The functions are wrapped for the flight's duration only (and restored after it); the wrapping
itself costs about a microsecond per call, charged to the part that made the call.  The flight's
rows are those of an unwrapped flight (``tests/cosim/test_fly_breakdown.py``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

import robosoc.cosim.lockstep as lockstep
from robosoc.benchmarks.fly import WARM_UP_S, with_engine
from robosoc.chip.mpsoc import MPSoC
from robosoc.chip.translation import ChipTranslation
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig, vehicle_preset
from robosoc.cosim.firmware_run import FirmwareRun
from robosoc.cosim.lockstep import ChipController, fly_lockstep
from robosoc.kernels import chip as kc
from robosoc.kernels.core_layout import C_IRQ
from robosoc.kernels.host_ticks import read_ticks
from robosoc.physics import World
from robosoc.physics.clock import FlightClock
from robosoc.physics.world import Quadrotor

LOOP = "lockstep loop (rest)"
CHIP_CALLS = "chip loop: calls"
#: the chip loop's parts, as it counts them (gst slot of its ticks, of its count)
KERNEL_PARTS: tuple[tuple[str, int, int | None], ...] = (
    ("chip loop: interpreter", kc.G_TK_INTERP, kc.G_N_INTERP),
    ("chip loop: translated", kc.G_TK_JIT, kc.G_N_JIT),
    ("chip loop: NI accesses", kc.G_TK_NI, kc.G_N_NI),
    ("chip loop: wake-ups", kc.G_TK_WAKE, kc.G_N_WAKE),
    ("chip loop: NoC", kc.G_TK_NOC, None),
)
BOOKKEEPING = "chip loop: quanta"
#: the functions timed, in the order printed: (owner, attribute, part)
WRAPPED: tuple[tuple[Any, str, str], ...] = (
    (World, "step", "physics"),
    (Quadrotor, "sensors", "sensors"),
    (lockstep, "flight_row", "flight rows"),
    (ChipController, "sense", "sample in"),
    (FirmwareRun, "close_period", "period close"),
    (ChipController, "advance", "commands out"),
    (FirmwareRun, "run_to", "chip messages"),
    (MPSoC, "step", "chip step (Python)"),
    (ChipTranslation, "prepare", "translation upkeep"),
    (ChipTranslation, "translate", "translation upkeep"),
    (kc, "run_chip", CHIP_CALLS),
    (ChipController, "finish", "flight end"),
)


@dataclass(frozen=True)
class Part:
    """One cause: its host seconds and how often it happened (None: not counted)."""

    name: str
    seconds: float
    count: int | None


@dataclass(frozen=True)
class FlightBreakdown:
    """Where one flight's host time went (see the module doc)."""

    firmware: FirmwareConfig
    parts: tuple[Part, ...]
    total_s: float  # measured around the whole flight
    simulated_s: float
    physics_steps: int
    chip_loop_calls: int
    quanta: int
    interrupt_entries: int
    sleeps: int
    rows: np.ndarray

    @property
    def parts_s(self) -> float:
        """The parts' sum (equals ``total_s`` but for the clock reads outside the sections)."""
        return sum(p.seconds for p in self.parts)

    def part(self, name: str) -> Part:
        return next(p for p in self.parts if p.name == name)


class _Sections:
    """Exclusive host time per section: entering one charges the time so far to the one it interrupts."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self._stack: list[str] = []
        self._mark = 0.0

    def enter(self, name: str) -> None:
        now = time.perf_counter()
        if self._stack:
            top = self._stack[-1]
            self.seconds[top] = self.seconds.get(top, 0.0) + now - self._mark
        self._stack.append(name)
        self.calls[name] = self.calls.get(name, 0) + 1
        self._mark = now

    def leave(self) -> None:
        now = time.perf_counter()
        top = self._stack.pop()
        self.seconds[top] = self.seconds.get(top, 0.0) + now - self._mark
        self._mark = now

    def wrap(self, name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: Any, **kwargs: Any) -> Any:
            self.enter(name)
            try:
                return fn(*args, **kwargs)
            finally:
                self.leave()

        return timed


@contextlib.contextmanager
def _wrapped(sections: _Sections, ticks: dict[int, int]) -> Iterator[None]:
    """The functions of :data:`WRAPPED` timed; the chip loop counting its ticks into ``ticks``."""
    saved = [(owner, attr, owner.__dict__[attr]) for owner, attr, _ in WRAPPED]
    slots = [kc.G_TK_CALL, kc.G_N_SLEEP] + [s for _, tk, n in KERNEL_PARTS for s in (tk, n) if s is not None]

    def run_chip(core: Any, noc: Any, book: kc.ChipBook, *args: Any) -> int:
        book.gst[kc.G_PROF] = 1
        try:
            return int(saved_run_chip(core, noc, book, *args))
        finally:
            book.gst[kc.G_PROF] = 0
            for s in slots:
                ticks[s] = ticks.get(s, 0) + int(book.gst[s])
                book.gst[s] = 0

    saved_run_chip = kc.run_chip
    try:
        for owner, attr, name in WRAPPED:
            fn = run_chip if owner is kc and attr == "run_chip" else owner.__dict__[attr]
            setattr(owner, attr, sections.wrap(name, fn))
        yield
    finally:
        for owner, attr, fn in saved:
            setattr(owner, attr, fn)


def fly_breakdown(scenario: ScenarioConfig, vehicle: VehicleConfig | None = None) -> FlightBreakdown:
    """Fly ``scenario`` with its firmware on its chip and break the flight's host time down by cause.

    The firmware is built (and the controller made) before the timed flight; compile the kernels
    first (a short flight) for a breakdown of a warm flight.
    """
    vehicle = vehicle or vehicle_preset(scenario.vehicle)
    controller = ChipController(scenario, vehicle, timeline=False)  # as robosoc bench fly flies it
    sections = _Sections()
    ticks: dict[int, int] = {}
    with _wrapped(sections, ticks):
        tick0, start = read_ticks(), time.perf_counter()
        sections.enter(LOOP)
        rows = fly_lockstep(scenario, vehicle, controller)
        sections.leave()
        tick1, total = read_ticks(), time.perf_counter() - start
    rate = (tick1 - tick0) / total  # host cycle-counter ticks per second over the flight
    seconds, calls = sections.seconds, sections.calls
    parts: list[Part] = []
    for name in dict.fromkeys(name for _, _, name in WRAPPED if name != CHIP_CALLS):
        parts.append(Part(name, seconds.get(name, 0.0), calls.get(name, 0)))
    parts.append(Part(LOOP, seconds.get(LOOP, 0.0), None))
    in_loop = ticks.get(kc.G_TK_CALL, 0)
    counted = 0
    for name, tk, n in KERNEL_PARTS:
        counted += ticks.get(tk, 0)
        parts.append(Part(name, ticks.get(tk, 0) / rate, None if n is None else ticks.get(n, 0)))
    parts.append(Part(BOOKKEEPING, (in_loop - counted) / rate, None))
    parts.append(Part(CHIP_CALLS, seconds.get(CHIP_CALLS, 0.0) - in_loop / rate, calls.get(CHIP_CALLS, 0)))
    run = controller.run
    assert run is not None
    return FlightBreakdown(
        firmware=scenario.firmware,
        parts=tuple(parts),
        total_s=total,
        simulated_s=FlightClock.of(scenario).simulated_s(len(rows)),
        physics_steps=calls.get(WRAPPED[0][2], 0),
        chip_loop_calls=calls.get(CHIP_CALLS, 0),
        quanta=int(run.chip.gst[kc.G_QUANTA]),
        interrupt_entries=int(run.chip.cores.ctr[:, C_IRQ].sum()),
        sleeps=ticks.get(kc.G_N_SLEEP, 0),
        rows=rows,
    )


def print_breakdown(breakdown: FlightBreakdown, console: Console) -> None:
    """The parts as a table: seconds, share of the flight, µs per physics step, count per step."""
    steps = max(breakdown.physics_steps, 1)
    b = breakdown
    console.print(
        f"chip {b.firmware.label}: {b.simulated_s:g} s simulated in {b.total_s:.3f} s "
        f"({b.simulated_s / b.total_s:.2f}× real time); per physics step: {b.chip_loop_calls / steps:.2f} "
        f"chip loop calls, {b.quanta / steps:.1f} quanta, {b.interrupt_entries / steps:.2f} interrupt "
        f"entries, {b.sleeps / steps:.2f} sleeps"
    )
    table = Table(show_edge=False, pad_edge=False)
    for header in ("part", "seconds", "share", "µs/step", "count/step"):
        table.add_column(header, justify="left" if header == "part" else "right")
    for p in sorted(b.parts, key=lambda p: -p.seconds):
        table.add_row(
            p.name,
            f"{p.seconds:.4f}",
            f"{100 * p.seconds / b.total_s:.1f} %",
            f"{1e6 * p.seconds / steps:.2f}",
            "-" if p.count is None else f"{p.count / steps:.2f}",
        )
    table.add_row("sum of the parts", f"{b.parts_s:.4f}", f"{100 * b.parts_s / b.total_s:.1f} %", "", "")
    table.add_row("measured flight", f"{b.total_s:.4f}", "100.0 %", f"{1e6 * b.total_s / steps:.2f}", "")
    console.print(table)


def run_fly_breakdown(
    builds: tuple[FirmwareConfig, ...],
    duration_s: float = 10.0,
    console: Console | None = None,
    engine: str | None = None,
) -> list[FlightBreakdown]:
    """Per build: a short flight to compile, then the breakdown of a ``duration_s`` flight, printed
    (``engine``: the chip's engine; default: the default scenario's chip's).

    Raises:
        ValueError: no build, ``duration_s`` is not a whole number of ms of at least one sensor
            period, or ``engine`` names none.
    """
    if not builds:
        raise ValueError("builds: at least one firmware build")
    console = console or Console()
    base = with_engine(ScenarioConfig(duration_s=duration_s), engine)
    console.print(
        f"where the host time of a lockstep flight goes, {duration_s:g} s simulated per build, "
        f"chip engine {base.chip.engine}"
    )
    out = []
    for fw in builds:
        scenario = dataclasses.replace(base, firmware=fw)
        # build, compile and enter auto's translations outside the timing (as bench fly does)
        fly_breakdown(dataclasses.replace(scenario, duration_s=min(WARM_UP_S, duration_s)))
        breakdown = fly_breakdown(scenario)
        print_breakdown(breakdown, console)
        out.append(breakdown)
    return out


__all__ = ["FlightBreakdown", "Part", "fly_breakdown", "print_breakdown", "run_fly_breakdown"]
