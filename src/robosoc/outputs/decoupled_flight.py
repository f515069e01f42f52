"""The decoupled mode as a whole: each side with its files, and both sides as processes.

* :func:`run_physics_side` / :func:`run_chip_side`: one side (``robosoc serve physics|chip``) with
  its files in the run folder: ``flight.csv`` (as it flies; after the flight's columns one per
  telemetry value the project publishes under a name of its own, as lockstep's),
  ``link-physics.log``, ``physics.json``; ``jobs.csv``, ``link-chip.log``, ``chip.json``.
* :func:`fly_decoupled` (``robosoc fly --decoupled``): starts both sides as separate processes
  (``multiprocessing``, spawn start method), the physics first on a free loopback port, then the
  chip pointed at it; they talk only over UDP.  The processes report their progress through a
  pipe; at the end the two sides' parts become ``summary.json`` (``"mode": "decoupled"``, with the
  ``"link"`` counts).  Ctrl-C reaches both sides (the terminal's process group, and forwarded);
  each ends, says bye and writes what it did, and the summary is written with ``"complete": false``.
"""

from __future__ import annotations

import contextlib
import json
import math
import multiprocessing
import os
import signal
import threading
import time
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from pathlib import Path
from typing import Any

from robosoc.config.link import LinkConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig, vehicle_preset
from robosoc.control.flight_log import CsvFlightLog
from robosoc.cosim.decoupled_chip import ChipOutcome, serve_chip
from robosoc.cosim.decoupled_physics import Ended, PhysicsOutcome, serve_physics, serve_physics_fleet
from robosoc.cosim.link import Address, LinkError
from robosoc.host.telemetry import declared_names, own_columns
from robosoc.outputs.decoupled_summary import chip_record, decoupled_summary, physics_record
from robosoc.outputs.flight_session import fleet_vehicles, min_separation, vehicle_folder
from robosoc.outputs.run_folder import (
    CHIP_JSON,
    FLIGHT_CSV,
    JOBS_CSV,
    LINK_CHIP_LOG,
    LINK_PHYSICS_LOG,
    PHYSICS_JSON,
    SUMMARY_JSON,
    write_jobs_csv,
)
from robosoc.outputs.run_summary import fleet_summary, write_summary
from robosoc.toolchain.errors import ToolchainError

__all__ = [
    "DecoupledFlight",
    "SideFailed",
    "fly_decoupled",
    "run_chip_side",
    "run_physics_fleet_side",
    "run_physics_side",
]

#: How long the sides get to end and write their files after Ctrl-C before they are terminated.
SHUTDOWN_S = 20.0


@contextlib.contextmanager
def _interrupts_held() -> Iterator[None]:
    """Ctrl-C is ignored while a side whose flight has ended writes what it did.

    A side may end because its peer said bye (the peer took its Ctrl-C first) and then receive its
    own: without this its record would be lost half written.  Signal handlers belong to the main
    thread; elsewhere this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def run_physics_side(
    scenario: ScenarioConfig,
    vehicle: VehicleConfig,
    config: LinkConfig,
    bind: Address,
    out: Path | None,
    **callbacks: Any,
) -> tuple[PhysicsOutcome, dict[str, Any]]:
    """:func:`serve_physics` writing ``flight.csv``, ``link-physics.log`` and ``physics.json`` in
    ``out`` (nothing if None); the outcome and the ``physics.json`` record.  The telemetry the chip
    must publish is the scenario's project's (:func:`robosoc.host.telemetry.declared_names`)."""
    telemetry = declared_names(scenario.firmware)
    log = CsvFlightLog(out / FLIGHT_CSV, own_columns(telemetry)) if out is not None else None
    try:
        outcome = serve_physics(
            scenario, vehicle, config, bind,
            log_path=out / LINK_PHYSICS_LOG if out is not None else None, telemetry=telemetry,
            on_row=log.write if log is not None else None,
            **callbacks,
        )  # fmt: skip
    finally:
        if log is not None:
            log.close()
    with _interrupts_held():
        record = physics_record(outcome, scenario, vehicle)
        if out is not None:
            write_summary(record, out / PHYSICS_JSON)
    return outcome, record


def run_physics_fleet_side(
    scenario: ScenarioConfig,
    config: LinkConfig,
    bind: Address,
    out: Path | None,
    **callbacks: Any,
) -> tuple[list[PhysicsOutcome], dict[str, Any]]:
    """:func:`serve_physics_fleet` for the scenario's vehicles, each vehicle's ``flight.csv``,
    ``link-physics.log`` and ``physics.json`` in its ``vehicle-N/`` folder of ``out``; the outcomes
    and ``{"vehicles": [physics.json records], "min_separation_m": ...}``."""
    vehicles = fleet_vehicles(scenario)
    telemetry = declared_names(scenario.firmware)
    folders, logs, on_row = fleet_logs(out, len(vehicles), own_columns(telemetry))

    try:
        outcomes = serve_physics_fleet(
            scenario, vehicles, vehicle_preset(scenario.vehicle), config, bind,
            log_paths=[f / LINK_PHYSICS_LOG if f is not None else None for f in folders], telemetry=telemetry,
            on_row=on_row, **callbacks,
        )  # fmt: skip
    finally:
        for log in logs:
            if log is not None:
                log.close()
    with _interrupts_held():
        records = []
        for outcome, vehicle, folder in zip(outcomes, vehicles, folders, strict=True):
            record = physics_record(outcome, scenario, vehicle)
            if folder is not None:
                write_summary(record, folder / PHYSICS_JSON)
            records.append(record)
    return outcomes, {"vehicles": records, "min_separation_m": min_separation([o.rows for o in outcomes])}


def run_chip_side(
    scenario: ScenarioConfig,
    vehicle: VehicleConfig,
    config: LinkConfig,
    peer: Address | str,
    bind: Address | None,
    out: Path | None,
    *,
    on_status: Callable[[str], None] | None = None,
    **link: Any,
) -> tuple[ChipOutcome, dict[str, Any]]:
    """:func:`serve_chip` writing ``jobs.csv``, ``link-chip.log`` and ``chip.json`` in ``out``
    (``link``: its ``transport`` and ``on_period``, for the ROS node)."""
    outcome = serve_chip(
        scenario, vehicle, config, peer, bind,
        log_path=out / LINK_CHIP_LOG if out is not None else None, on_status=on_status, **link,
    )  # fmt: skip
    with _interrupts_held():
        record = chip_record(outcome, scenario.firmware, scenario.chip)
        if out is not None:
            if outcome.result is not None:
                write_jobs_csv(outcome.result.jobs, out / JOBS_CSV)
            write_summary(record, out / CHIP_JSON)
    return outcome, record


# --- both sides as processes ---------------------------------------------------------------------


class SideFailed(Exception):
    """A side could not start or crashed: ``side`` names it, ``kind`` is "link" (its address),
    "build" (the firmware) or "internal"."""

    def __init__(self, side: str, kind: str, message: str) -> None:
        super().__init__(f"{side} side: {message}")
        self.side, self.kind, self.message = side, kind, message


def _interrupt_once() -> None:
    """The first Ctrl-C interrupts the side; later ones (the terminal's and the parent's) must not
    interrupt it while it ends and writes its files."""

    def handler(signum: int, frame: object) -> None:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        raise KeyboardInterrupt

    signal.signal(signal.SIGINT, handler)


def _send(conn: Connection, *message: object) -> None:
    with contextlib.suppress(OSError, EOFError):  # the parent has gone: the side goes on and writes its files
        conn.send(message)


def _physics_process(conn: Connection, args: tuple) -> None:
    _physics_side(conn, run_physics_side, args, "physics: the chip said hello; flying")


def _physics_fleet_process(conn: Connection, args: tuple) -> None:
    _physics_side(conn, run_physics_fleet_side, args, "physics: every chip said hello; flying")


def _physics_side(conn: Connection, side: Callable[..., Any], args: tuple, started: str) -> None:
    """One physics side's process (one vehicle's or a fleet's): its events to the parent."""
    _interrupt_once()
    _report(
        conn,
        lambda: side(
            *args,
            on_listen=lambda address: _send(conn, "listening", address),
            on_start=lambda: _send(conn, "status", started),
            on_sample=lambda done, total: _send(conn, "progress", done, total),
        ),
    )


def _chip_process(conn: Connection, args: tuple) -> None:
    _interrupt_once()

    def status(text: str) -> None:
        _send(conn, "status", f"chip: {text}")

    _report(conn, lambda: run_chip_side(*args, on_status=status))


def fleet_logs(
    out: Path | None, count: int, telemetry: tuple[str, ...] = ()
) -> tuple[list[Path | None], list[CsvFlightLog | None], Callable[[int, Any, tuple[float, ...]], None]]:
    """Each of ``count`` vehicles' folder in ``out`` (made; None without ``out``), its ``flight.csv``
    log (``telemetry``: the columns after the flight's), and ``on_row(i, row, values)`` writing a
    row of vehicle i's flight with its telemetry values to its log."""
    folders = [vehicle_folder(out, i, count) if out is not None else None for i in range(count)]
    for folder in folders:
        if folder is not None:
            folder.mkdir(parents=True, exist_ok=True)
    logs = [CsvFlightLog(f / FLIGHT_CSV, telemetry) if f is not None else None for f in folders]

    def on_row(i: int, row: Any, values: tuple[float, ...]) -> None:
        log = logs[i]
        if log is not None:
            log.write(row, values)

    return folders, logs, on_row


def _interrupt(sides: list[_Side], say: Callable[[str], None]) -> None:
    """Ctrl-C: pass it on to every side and collect what they send while they end."""
    for side in sides:
        side.interrupt()
    _collect(sides, say, None, deadline=time.monotonic() + SHUTDOWN_S)


def _join(sides: list[_Side], interrupted: bool) -> None:
    """Wait for every side's process; one that does not end in time is terminated (none is left)."""
    for side in sides:
        side.process.join(timeout=SHUTDOWN_S if not interrupted else 1.0)
        if side.process.is_alive():
            side.process.terminate()
            side.process.join(timeout=5.0)


def _report(conn: Connection, side: Callable[[], tuple[Any, dict]]) -> None:
    """Run one side and send its record, or how it failed, to the parent."""
    try:
        _, record = side()
        _send(conn, "done", record)
    except LinkError as exc:
        _send(conn, "error", "link", str(exc))
    except ToolchainError as exc:  # the firmware does not build (a compile error, or too big for SRAM)
        _send(conn, "error", "build", f"the firmware does not build: {exc}")
    except KeyboardInterrupt:
        _send(conn, "error", "interrupted", "interrupted before the flight")
    except BaseException:
        _send(conn, "error", "internal", traceback.format_exc())


@dataclass
class DecoupledFlight:
    """The two sides' records, the summary, and how the flight ended."""

    summary: dict[str, Any]
    physics: dict[str, Any] = field(default_factory=dict)
    chip: dict[str, Any] = field(default_factory=dict)
    interrupted: bool = False
    #: with several vehicles: each vehicle's (physics.json, chip.json) records, the first also above
    vehicles: list[tuple[dict[str, Any], dict[str, Any]]] = field(default_factory=list)

    def _records(self) -> list[dict[str, Any]]:
        pairs = self.vehicles or [(self.physics, self.chip)]
        return [p for p, _ in pairs] + [c for _, c in pairs]

    @property
    def ended(self) -> str:
        """The first reason that is not ``done``: the physics side's, else a chip side's."""
        if self.interrupted:
            return Ended.INTERRUPTED
        for record in self._records():
            if record.get("ended", Ended.FAILED) != Ended.DONE:
                return str(record.get("ended", Ended.FAILED))
        return Ended.DONE

    @property
    def message(self) -> str:
        for record in self._records():
            if record.get("ended") not in (None, Ended.DONE):
                return f"{record.get('side')} side: {record.get('message')}"
        return "interrupted" if self.interrupted else "flown"


class _Side:
    def __init__(self, name: str, ctx: Any, target: Callable, args: tuple) -> None:
        self.name = name
        self.conn, child = ctx.Pipe(duplex=False)
        self.process = ctx.Process(target=target, args=(child, *args), name=f"robosoc-{name}", daemon=False)
        self.process.start()
        child.close()
        self.record: dict[str, Any] | None = None
        self.error: tuple[str, str] | None = None
        self.address: Any = None  # where the physics side listens (a list: one per vehicle), once it says
        self.open = True

    def receive(self) -> list[tuple]:
        out = []
        try:
            while self.conn.poll():
                out.append(self.conn.recv())
        except (EOFError, OSError):
            self.open = False
        return out

    @property
    def finished(self) -> bool:
        return self.record is not None or self.error is not None or (not self.open and not self.process.is_alive())

    def interrupt(self) -> None:
        if self.process.is_alive() and self.process.pid is not None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(self.process.pid, signal.SIGINT)


def fly_decoupled(
    scenario: ScenarioConfig,
    vehicle: VehicleConfig,
    config: LinkConfig,
    out: Path,
    *,
    bind: Address | None = None,
    on_status: Callable[[str], None] | None = None,
    on_progress: Callable[[int, int], None] | None = None,
) -> DecoupledFlight:
    """Fly ``scenario`` (its firmware on its chip) with the physics and the chip in two processes
    talking UDP; files in ``out``.

    Args:
        bind: the physics side's address (default: a free port on 127.0.0.1).
        on_status: told what the sides are doing (building, booting, flying).
        on_progress: called with (samples flown, samples in all).

    Returns:
        Both sides' records and ``summary.json``'s contents (also written), also when a side
        lost its peer or the flight was interrupted.

    Raises:
        SideFailed: a side could not bind its address or crashed (the message says which and why).
    """
    out.mkdir(parents=True, exist_ok=True)
    bind = bind or Address("127.0.0.1", 0)
    ctx = multiprocessing.get_context("spawn")
    say = on_status or (lambda _text: None)
    if scenario.vehicles > 1:
        return _fly_fleet(scenario, vehicle, config, out, bind, ctx, say, on_progress)
    sides: list[_Side] = []
    interrupted = False
    try:
        physics = _Side("physics", ctx, _physics_process, ((scenario, vehicle, config, bind, out),))
        sides.append(physics)
        address = _await_listening(physics, config.connect_timeout_s, say)
        chip_side = _Side("chip", ctx, _chip_process, ((scenario, vehicle, config, address, None, out),))
        sides.append(chip_side)
        _collect(sides, say, on_progress, deadline=None)
    except KeyboardInterrupt:
        interrupted = True
        _interrupt(sides, say)
    finally:
        _join(sides, interrupted)
    failed = [s for s in sides if s.error is not None and s.error[0] in ("link", "build", "internal")]
    records = {s.name: s.record or _read_record(out / f"{s.name}.json") for s in sides}
    result = DecoupledFlight(
        summary={},
        physics=records.get("physics") or {},
        chip=records.get("chip") or {},
        interrupted=interrupted or any(s.error is not None and s.error[0] == "interrupted" for s in sides),
    )
    result.summary = decoupled_summary(result.physics, result.chip, scenario=scenario, config=config)
    write_summary(result.summary, out / SUMMARY_JSON)
    if failed and not interrupted:
        side = failed[0]
        assert side.error is not None
        raise SideFailed(side.name, side.error[0], side.error[1])
    for side in sides:
        if side.record is None and side.error is None and not interrupted:
            raise SideFailed(side.name, "internal", f"the process ended with exit code {side.process.exitcode}")
    return result


def _fly_fleet(
    scenario: ScenarioConfig,
    vehicle: VehicleConfig,
    config: LinkConfig,
    out: Path,
    bind: Address,
    ctx: Any,
    say: Callable[[str], None],
    on_progress: Callable[[int, int], None] | None,
) -> DecoupledFlight:
    """:func:`fly_decoupled` with several vehicles: one physics process flying them all in one world
    (:func:`run_physics_fleet_side`), one chip process per vehicle, each on its own UDP link;
    ``vehicle-N/`` folders with each vehicle's files and ``summary.json``, and the fleet's summary."""
    count = scenario.vehicles
    folders = [vehicle_folder(out, i, count) for i in range(count)]
    for folder in folders:
        folder.mkdir(parents=True, exist_ok=True)
    sides: list[_Side] = []
    interrupted = False
    try:
        physics = _Side("physics", ctx, _physics_fleet_process, ((scenario, config, bind, out),))
        sides.append(physics)
        addresses = _await_listening(physics, config.connect_timeout_s, say)
        assert isinstance(addresses, list)
        for i, (address, folder) in enumerate(zip(addresses, folders, strict=True)):
            args = ((scenario, vehicle, config, address, None, folder),)
            sides.append(_Side(f"chip {i + 1}", ctx, _chip_process, args))
        _collect(sides, say, on_progress, deadline=None)
    except KeyboardInterrupt:
        interrupted = True
        _interrupt(sides, say)
    finally:
        _join(sides, interrupted)
    physics_part = sides[0].record or {} if sides else {}
    physics_records = list(physics_part.get("vehicles") or [])
    physics_records += [_read_record(f / PHYSICS_JSON) for f in folders[len(physics_records) :]]
    chip_records = [
        (sides[i + 1].record if i + 1 < len(sides) else None) or _read_record(folders[i] / CHIP_JSON)
        for i in range(count)
    ]
    summaries = []
    for p, c, folder in zip(physics_records, chip_records, folders, strict=True):
        summary = decoupled_summary(p, c, scenario=scenario, config=config)
        write_summary(summary, folder / SUMMARY_JSON)
        summaries.append(summary)
    simulated = max((float(p.get("simulated_s", 0.0)) for p in physics_records), default=0.0)
    host = max((float(p.get("host_s", 0.0)) for p in physics_records), default=0.0)
    stopped_early = interrupted or any(s.error is not None and s.error[0] == "interrupted" for s in sides)
    top = fleet_summary(
        scenario, summaries, simulated, host, min_separation_m=float(physics_part.get("min_separation_m", math.nan)),
        complete=all(s["complete"] for s in summaries),
    )  # fmt: skip
    top["mode"] = "decoupled"
    write_summary(top, out / SUMMARY_JSON)
    failed = [s for s in sides if s.error is not None and s.error[0] in ("link", "internal")]
    if failed and not interrupted:
        side = failed[0]
        assert side.error is not None
        raise SideFailed(side.name, side.error[0], side.error[1])
    for side in sides:
        if side.record is None and side.error is None and not interrupted:
            raise SideFailed(side.name, "internal", f"the process ended with exit code {side.process.exitcode}")
    return DecoupledFlight(
        summary=top, physics=physics_records[0], chip=chip_records[0], interrupted=stopped_early,
        vehicles=list(zip(physics_records, chip_records, strict=True)),
    )  # fmt: skip


def _read_record(path: Path) -> dict[str, Any]:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}


def _handle(side: _Side, message: tuple, say: Callable[[str], None], on_progress: Callable | None) -> None:
    kind = message[0]
    if kind == "status":
        say(message[1])
    elif kind == "progress" and on_progress is not None:
        on_progress(message[1], message[2])
    elif kind == "done":
        side.record = message[1]
    elif kind == "error":
        side.error = (message[1], message[2])
    elif kind == "listening":
        side.address = message[1]


def _await_listening(side: _Side, timeout_s: float, say: Callable[[str], None]) -> Any:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        wait([side.conn, side.process.sentinel], timeout=0.2)
        for message in side.receive():
            _handle(side, message, say, None)
        if side.address is not None:
            return side.address
        if side.error is not None:
            raise SideFailed(side.name, side.error[0], side.error[1])
        if not side.process.is_alive() and not side.conn.poll():
            raise SideFailed(side.name, "internal", f"the process ended with exit code {side.process.exitcode}")
    raise SideFailed(side.name, "internal", f"not listening after {timeout_s:g} s")


def _collect(
    sides: list[_Side], say: Callable[[str], None], on_progress: Callable | None, deadline: float | None
) -> None:
    """Take the sides' messages until each has finished (or ``deadline``); a side that failed to
    start or crashed gets the other one interrupted (it would wait for its peer in vain)."""
    stopped = False
    while not all(s.finished for s in sides):
        if deadline is not None and time.monotonic() > deadline:
            return
        waitables = [s.conn for s in sides if s.open] + [s.process.sentinel for s in sides if s.process.is_alive()]
        wait(waitables, timeout=0.5)
        for side in sides:
            for message in side.receive():
                _handle(side, message, say, on_progress)
        failed = any(s.error is not None or (s.finished and s.record is None) for s in sides)
        if failed and not stopped:
            stopped = True
            for side in sides:
                if not side.finished:
                    side.interrupt()
