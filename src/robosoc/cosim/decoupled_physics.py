"""The physics side of the decoupled mode (``robosoc serve physics``): the world, paced, over UDP.

The loop of :func:`serve_physics` is that of :func:`robosoc.cosim.lockstep.fly_lockstep` with the
chip at the other end of a UDP link (docs/decoupled.md):

1. it listens, and waits for the chip's hello (``connect_timeout_s``), which must name the same
   scenario and vehicle (:func:`scenario_digest`);
2. per sensor sample k at ``t_k``: the flight row is formed and the sample's sensor packet sent in
   a sensor batch with its timestamp (plus the ``resend`` readings before it);
3. per sample period (the 1 ms physics steps from ``t_k`` to ``t_k+1``): it waits until the steps
   may be taken -- ``pace="realtime"``: the wall clock has reached ``t_k+1`` since the start;
   ``pace="fast"``: the chip has reported reaching ``t_k+1`` (so every command that left the chip
   before is known) -- meanwhile taking the datagrams that come.  Each command is scheduled at
   the step of the chip time it left or, if it came later than that, at the step it arrived in
   (realtime: the step the wall clock was in; counted late); then the world takes the period's
   steps with what :class:`~robosoc.cosim.actuator_hold.ActuatorHold` gives for each;
4. at the end it sends a bye and waits (up to ``peer_timeout_s``) for the chip's, which says how
   many datagrams the chip sent.

The chip's telemetry (its project's ``[[telemetry]]`` values, the estimate among them) comes in
telemetry datagrams; the hello names the values, which must be the names the physics side was
given (those of the scenario's project).  Row k shows the newest entry of a sample before k that
has come (:class:`~robosoc.cosim.telemetry_rows.TelemetryRows`), as lockstep's row does.

A side that waits repeats its newest datagram every ``heartbeat_s`` (a lost datagram cannot stall
the flight), and ends when the peer has been silent for ``peer_timeout_s``.  With ``pace="fast"``
and every command delivered in time the flight is the lockstep flight, row for row.
"""

from __future__ import annotations

import dataclasses
import hashlib
import select
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robosoc.config.link import LinkConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.control.flight import ROW_FIELDS, flight_row
from robosoc.control.setpoint import setpoint_at
from robosoc.cosim.actuator_hold import ActuatorHold
from robosoc.cosim.datagram import (
    MAX_READINGS,
    Bye,
    ByeReason,
    CommandBatch,
    Hello,
    Reading,
    SensorBatch,
    TelemetryBatch,
)
from robosoc.cosim.link import Address, LinkLog, UdpLink
from robosoc.cosim.lockstep import PWM_COLUMNS, UNKNOWN_ESTIMATE
from robosoc.cosim.replay import sensor_packet
from robosoc.cosim.telemetry_rows import TelemetryRows
from robosoc.physics import World
from robosoc.physics.clock import NS_PER_S, PHYSICS_STEP_NS, FlightClock

__all__ = [
    "Ended",
    "PhysicsOutcome",
    "fleet_binds",
    "scenario_digest",
    "serve_physics",
    "serve_physics_fleet",
]


class Ended:
    """How a side's run ended (``outcome.ended``)."""

    DONE = "done"
    INTERRUPTED = "interrupted"
    PEER_LOST = "peer_lost"  # the peer was silent for peer_timeout_s, or never answered
    PEER_ENDED = "peer_ended"  # the peer said bye before the end (interrupted, failed)
    MISMATCH = "mismatch"  # the chip's firmware was built for another scenario or vehicle
    FAILED = "failed"  # this side failed (the firmware faulted on the chip)


def scenario_digest(scenario: ScenarioConfig, vehicle: VehicleConfig) -> bytes:
    """8 bytes naming what a chip's firmware is built for: both sides must have it equal.  The
    number of vehicles is left out: every chip of a fleet runs the same firmware."""
    return hashlib.blake2b(repr((dataclasses.replace(scenario, vehicles=1), vehicle)).encode(), digest_size=8).digest()


@dataclass
class PhysicsOutcome:
    """What the physics side did: the rows flown, how it ended, the link's counts."""

    rows: np.ndarray
    samples: int
    ended: str
    message: str
    host_s: float
    cpu_s: float
    link: dict[str, object] = field(default_factory=dict)
    commands: dict[str, int] = field(default_factory=dict)
    max_lag_s: float = 0.0
    period_s: float = 0.0
    #: the firmware's telemetry under names of its own: name -> one value per row (NaN before the first)
    telemetry: dict[str, np.ndarray] = field(default_factory=dict)
    #: the chip's telemetry entries kept (``received``) and datagrams refused (not a value per name)
    telemetry_counts: dict[str, int] = field(default_factory=dict)

    @property
    def simulated_s(self) -> float:
        """Simulated seconds flown (whole sample periods)."""
        return len(self.rows) * self.period_s

    @property
    def complete(self) -> bool:
        return self.ended == Ended.DONE


class PeerSilent(Exception):
    pass


class PeerEnded(Exception):
    pass


class Mismatch(Exception):
    pass


class _Flight:
    """State of one flight on the physics side (the helpers of :func:`serve_physics`)."""

    def __init__(
        self, link: UdpLink, config: LinkConfig, hold: ActuatorHold, log: LinkLog, telemetry: TelemetryRows
    ) -> None:
        self.link, self.config, self.hold, self.log = link, config, hold, log
        self.progress_ns = -1
        self.newest_seq = -1
        self.first_step = 0  # the sample period being waited for: its first and last physics step
        self.last_step = 0
        self.start = time.monotonic()  # wall-clock time of flight time 0 (realtime pacing)
        self.received = self.late = 0
        self.recent: deque[Reading] = deque(maxlen=min(MAX_READINGS, config.resend + 1))
        self.last_send = time.monotonic()
        self.peer_bye: Bye | None = None
        self.finished = False  # the flight is over: commands are still counted, no longer applied
        self.telemetry = telemetry
        self.refused = 0  # telemetry datagrams whose entries do not hold a value per name of the hello
        self.told: list[tuple[float, ...]] = []  # each row's own telemetry values

    def send(self, now_ns: int, fresh: list[Reading]) -> None:
        self.recent.extend(fresh)
        self.link.send_data(SensorBatch(now_ns, tuple(self.recent)))
        self.last_send = time.monotonic()

    def take(self, timeout: float) -> bool:
        """Receive for up to ``timeout`` s; whether anything valid came."""
        got = self.link.receive(timeout)
        for d in got:
            body = d.body
            if isinstance(body, CommandBatch):
                self.progress_ns = max(self.progress_ns, body.chip_now_ns)
                for c in body.commands:
                    if c.seq <= self.newest_seq:
                        continue  # a repeat, or older than a command already scheduled
                    self.newest_seq = c.seq
                    self.received += 1
                    if self.finished:
                        continue
                    step = c.left_ns // PHYSICS_STEP_NS
                    now = self.arrival_step()
                    if step < now:
                        self.late += 1
                        self.log.write(
                            f"command {c.seq} (left at {c.left_ns} ns) applied late, at step {now}", "late command"
                        )
                        step = now
                    self.hold.schedule(step, c.pwm)
            elif isinstance(body, TelemetryBatch):
                if not all([self.telemetry.arrive(e.k, e.values) for e in body.entries]):
                    self.refused += 1
                    self.log.write(
                        f"telemetry #{d.seq} refused: entries of {len(body.entries[0].values)} values, the hello "
                        f"named {len(self.telemetry.names)}",
                        "telemetry refused",
                    )
            elif isinstance(body, Bye):
                self.peer_bye = body
                raise PeerEnded(f"the chip said bye ({body.reason.name.lower()})")
        return bool(got)

    def arrival_step(self) -> int:
        """The first physics step a command arriving now can act on: realtime, the step the wall
        clock is in (within the period being waited for); fast, the period's first step."""
        if self.config.pace == "fast":
            return self.first_step
        wall = int((time.monotonic() - self.start) * NS_PER_S) // PHYSICS_STEP_NS
        return min(max(wall, self.first_step), self.last_step)

    def check_peer(self) -> None:
        silent = self.link.silent_for(time.monotonic())
        if silent > self.config.peer_timeout_s:
            raise PeerSilent(
                f"no datagram from the chip for {silent:.1f} s (--peer-timeout {self.config.peer_timeout_s:g})"
            )

    def heartbeat(self, now_ns: int) -> None:
        if time.monotonic() - self.last_send >= self.config.heartbeat_s and self.recent:
            self.link.send_data(SensorBatch(now_ns, tuple(self.recent)))
            self.last_send = time.monotonic()


def _wait_for_hello(
    link: UdpLink, config: LinkConfig, digest: bytes, period_ns: int, telemetry: tuple[str, ...]
) -> Hello:
    deadline = time.monotonic() + config.connect_timeout_s
    while True:
        for d in link.receive(min(0.1, max(0.0, deadline - time.monotonic()))):
            if isinstance(d.body, Hello):
                if d.body.digest != digest or d.body.sample_period_ns != period_ns:
                    raise Mismatch(
                        "the chip's firmware was built for another scenario or vehicle "
                        "(give both sides the same --scenario, --seconds and --vehicle)"
                    )
                if d.body.telemetry != telemetry:
                    raise Mismatch(
                        f"the chip's firmware publishes the telemetry {_listed(d.body.telemetry)}, the scenario's "
                        f"project declares {_listed(telemetry)} (give both sides the same project)"
                    )
                return d.body
        if time.monotonic() > deadline:
            versions = link.counts.rejected.get("bad_version", 0)
            hint = (
                f" ({versions} datagrams of another robosoc version came: give both sides the same version)"
                if versions else ""
            )  # fmt: skip
            raise PeerSilent(f"no hello from a chip within --connect-timeout {config.connect_timeout_s:g} s{hint}")


def _listed(names: tuple[str, ...]) -> str:
    return f"({', '.join(names)})" if names else "(none)"


def serve_physics(
    scenario: ScenarioConfig,
    vehicle: VehicleConfig,
    config: LinkConfig,
    bind: Address,
    *,
    log_path: Path | None = None,
    telemetry: Sequence[str] = (),
    on_listen: Callable[[Address], None] | None = None,
    on_start: Callable[[], None] | None = None,
    on_row: Callable[[np.ndarray, tuple[float, ...]], None] | None = None,
    on_sample: Callable[[int, int], None] | None = None,
) -> PhysicsOutcome:
    """Fly ``scenario`` with the chip at the other end of a UDP link; see the module docstring.

    Args:
        scenario, vehicle: what is flown (as :func:`robosoc.cosim.lockstep.fly_lockstep`); the
            scenario's seed also drives the faults injected on the sensor batches.
        config: pacing, hold, timeouts, redundancy and faults.
        bind: the address to listen on (port 0: a free port, given to ``on_listen``).
        log_path: the side's link log (``link-physics.log``), or None.
        telemetry: the names of the telemetry values the chip's firmware publishes (its project's
            ``[[telemetry]]``, in order: :func:`robosoc.host.telemetry.declared_names`); a chip whose
            hello names others is refused.
        on_listen: called with the address bound, before waiting for the chip.
        on_start: called when the chip's hello has come and the flight starts.
        on_row: called with each row as soon as it is complete and the values of its own telemetry
            columns (:attr:`TelemetryRows.own <robosoc.cosim.telemetry_rows.TelemetryRows.own>`; the flight log).
        on_sample: called with (samples done, samples in all).

    Returns:
        The outcome, also when the flight was interrupted (Ctrl-C), the chip went silent or said
        bye early (``ended`` says which; the rows are those flown).

    Raises:
        LinkError: ``bind`` cannot be bound.
    """
    (outcome,) = serve_physics_fleet(
        scenario, [vehicle], vehicle, config, bind, log_paths=[log_path], telemetry=telemetry,
        on_listen=None if on_listen is None else lambda addresses: on_listen(addresses[0]),
        on_start=on_start, on_row=None if on_row is None else lambda _i, row, own: on_row(row, own),
        on_sample=on_sample,
    )  # fmt: skip
    return outcome


def fleet_binds(bind: Address, count: int) -> list[Address]:
    """Where the physics listens for each of ``count`` chips: ``bind``, then the ports after it
    (port 0: a free port each)."""
    return [Address(bind.host, bind.port + i if bind.port else 0) for i in range(count)]


def _wait_any(links: Sequence[UdpLink], timeout: float) -> None:
    """Wait up to ``timeout`` s until a datagram is there for one of ``links``."""
    try:
        select.select([link.sock for link in links], [], [], max(0.0, timeout))
    except (OSError, ValueError):
        time.sleep(min(timeout, 0.001))


def _wait_for_period(flights: Sequence[_Flight], config: LinkConfig, first_step: int, steps: int) -> float:
    """Wait until every vehicle's physics steps ``first_step ...`` of a sample period may be taken
    (their commands are known); the real-time lag then [s]."""
    for f in flights:
        f.first_step, f.last_step = first_step, first_step + steps - 1
    end_ns = (first_step + steps) * PHYSICS_STEP_NS
    start = flights[0].start
    while True:
        now = time.monotonic()
        if config.pace == "realtime":
            remaining = start + end_ns / NS_PER_S - now
            if remaining <= 0:
                for f in flights:
                    f.take(0.0)
                    f.check_peer()
                return -remaining
            timeout = min(remaining, config.heartbeat_s)
        else:
            if all(f.progress_ns >= end_ns for f in flights):
                return 0.0
            timeout = config.heartbeat_s
        _wait_any([f.link for f in flights], timeout)
        for f in flights:
            f.take(0.0)
            f.heartbeat(first_step * PHYSICS_STEP_NS)
            f.check_peer()


def serve_physics_fleet(
    scenario: ScenarioConfig,
    vehicles: Sequence[VehicleConfig],
    firmware_vehicle: VehicleConfig,
    config: LinkConfig,
    bind: Address,
    *,
    log_paths: Sequence[Path | None] | None = None,
    telemetry: Sequence[str] = (),
    on_listen: Callable[[list[Address]], None] | None = None,
    on_start: Callable[[], None] | None = None,
    on_row: Callable[[int, np.ndarray, tuple[float, ...]], None] | None = None,
    on_sample: Callable[[int, int], None] | None = None,
) -> list[PhysicsOutcome]:
    """Fly ``scenario`` with ``vehicles`` in one world, vehicle i flown by the chip at the other end
    of UDP link i (listening on :func:`fleet_binds`); each vehicle as :func:`serve_physics`, all
    under one clock (a period's steps wait for every chip).  The chips' firmware must have been built
    for ``scenario`` and ``firmware_vehicle`` (every chip of a fleet runs the same firmware) and
    publish the ``telemetry`` names.  ``on_row``: called with (vehicle index, row, its own telemetry values).

    Returns:
        Each vehicle's outcome (one ``ended`` for all: the first reason to stop).

    Raises:
        LinkError: an address cannot be bound.
    """
    clock = FlightClock.of(scenario)
    samples, period_ns = clock.sample_count, clock.sample_period_ns
    count = len(vehicles)
    paths = list(log_paths) if log_paths is not None else [None] * count
    logs = [LinkLog(path) for path in paths]
    links: list[UdpLink] = []
    try:
        for address, log in zip(fleet_binds(bind, count), logs, strict=True):
            links.append(UdpLink(address, "physics", config.faults, scenario.seed, log))
    except BaseException:
        for link in links:
            link.close()
        for log in logs:
            log.close()
        raise
    rows = [np.empty((samples, len(ROW_FIELDS))) for _ in vehicles]
    done = 0
    flights: list[_Flight] = []
    start = time.monotonic()
    cpu_start = time.process_time()
    ended, message = Ended.DONE, "flown"
    max_lag = 0.0
    try:
        if on_listen is not None:
            on_listen([link.address for link in links])
        digest = scenario_digest(scenario, firmware_vehicle)
        for i, (link, log) in enumerate(zip(links, logs, strict=True)):
            try:
                _wait_for_hello(link, config, digest, period_ns, tuple(telemetry))
            except (Mismatch, PeerSilent) as exc:
                raise type(exc)(f"vehicle {i + 1}: {exc}" if count > 1 else str(exc)) from None
            log.write(f"flying {samples} samples, pace {config.pace}, hold {config.hold}, resend {config.resend}")
        if on_start is not None:
            on_start()
        world = World(list(vehicles), scenario.sensors, scenario.wind)
        world.reset(scenario.seed)
        quads = world.quadrotors
        flights = [
            _Flight(link, config, ActuatorHold(config.hold, quad.pwm), log, TelemetryRows(telemetry))
            for link, log, quad in zip(links, logs, quads, strict=True)
        ]
        steps = clock.steps_per_sample
        start = time.monotonic()
        for f in flights:
            f.start = start
        cpu_start = time.process_time()
        pending: list[np.ndarray] = []
        for k in clock.samples():
            t_ns = clock.sample_ns(k)
            pending.clear()
            wind = world.wind.velocity
            for f, quad, craft in zip(flights, quads, vehicles, strict=True):
                sample = quad.sensors()
                setpoint = setpoint_at(scenario.flight, craft.rest_height, sample.time)
                row = flight_row(sample, quad.truth(), UNKNOWN_ESTIMATE, setpoint, quad.pwm, wind)
                f.send(t_ns, [Reading(k, t_ns, sensor_packet(row, k, period_ns // 1000))])
                pending.append(row)
            max_lag = max(max_lag, _wait_for_period(flights, config, clock.first_step(k), steps))
            for s, _ in clock.steps(k):
                for i, (f, quad) in enumerate(zip(flights, quads, strict=True)):
                    quad.apply_pwm(f.hold.at(clock.first_step(k) + s))
                    if s == 0:
                        row = pending[i]
                        row[PWM_COLUMNS] = quad.pwm
                        own = f.telemetry.fill(row, k)
                        f.told.append(own)
                        rows[i][k] = row
                        if on_row is not None:
                            on_row(i, row, own)
                if s == 0:
                    done = k + 1
                    if on_sample is not None:
                        on_sample(done, samples)
                world.step()
    except KeyboardInterrupt:
        ended, message = Ended.INTERRUPTED, "interrupted"
    except PeerSilent as exc:
        ended, message = Ended.PEER_LOST, str(exc)
    except PeerEnded as exc:
        ended, message = Ended.PEER_ENDED, str(exc)
    except Mismatch as exc:
        ended, message = Ended.MISMATCH, str(exc)
    finally:
        host_s = time.monotonic() - start
        cpu_s = time.process_time() - cpu_start
        reason = {Ended.DONE: ByeReason.DONE, Ended.INTERRUPTED: ByeReason.INTERRUPTED}.get(ended, ByeReason.ERROR)
        if ended == Ended.PEER_LOST:
            reason = ByeReason.PEER_LOST
        end_ns = samples * period_ns if ended == Ended.DONE else done * period_ns
        for i, (link, log) in enumerate(zip(links, logs, strict=True)):
            log.write(f"ended: {ended}: {message}")
            flight = flights[i] if flights else None
            try:
                if ended == Ended.DONE and flight is not None and flight.recent:
                    # the last readings once more: a reading lost at the very end has no later datagram to ride on
                    link.send_data(SensorBatch(samples * period_ns, tuple(flight.recent)))
                link.send_control(Bye(reason, link.sent, end_ns))
            except KeyboardInterrupt:
                pass
        outcomes = []
        for i, (link, log) in enumerate(zip(links, logs, strict=True)):
            flight = flights[i] if flights else None
            try:
                if ended == Ended.DONE and flight is not None:
                    _await_bye(flight, config)
            except KeyboardInterrupt:
                pass
            link.close()
            received = flight.received if flight else 0
            commands = {"received": received, "late": flight.late if flight else 0, "missed": max(0, done - received)}
            rows_telemetry = TelemetryRows(telemetry)
            shown = flight.told[:done] if flight else []
            told = np.array(shown, dtype=float).reshape(len(shown), len(rows_telemetry.own))
            outcome = PhysicsOutcome(
                rows=rows[i][:done],
                samples=samples,
                ended=ended,
                message=message,
                host_s=host_s,
                cpu_s=cpu_s,
                link=link.report(),
                commands=commands,
                max_lag_s=max_lag,
                period_s=period_ns / NS_PER_S,
                telemetry={name: told[:, c].copy() for c, name in enumerate(rows_telemetry.own)},
            )
            if flight is not None:
                outcome.telemetry_counts = {"received": flight.telemetry.received, "refused": flight.refused}
            log.write(f"counts: {outcome.link}; commands {commands}; telemetry {outcome.telemetry_counts}")
            log.close()
            outcomes.append(outcome)
    return outcomes


def _await_bye(flight: _Flight, config: LinkConfig) -> None:
    """After the flight: take what the chip still sends until its bye (or its silence)."""
    deadline = time.monotonic() + config.peer_timeout_s
    flight.finished = True
    while time.monotonic() < deadline:
        try:
            flight.take(min(0.05, deadline - time.monotonic()))
        except PeerEnded:
            return
