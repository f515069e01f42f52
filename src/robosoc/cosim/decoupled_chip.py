"""The chip side of the decoupled mode (``robosoc serve chip``): the firmware on the chip, over UDP.

:func:`serve_chip` runs the flight firmware (:class:`robosoc.cosim.firmware_run.FirmwareRun`) against
the readings the physics side sends (docs/decoupled.md):

* it boots the chip (to the cycle of flight time 0), then says hello to the physics side every
  ``heartbeat_s`` until the first sensor batch comes;
* **pacing**: the chip never runs past the physics' timestamps -- with readings waiting, up to the
  cycle of the oldest one; otherwise up to one sensor period past the newest reading injected (the
  earliest the next one can be due), or to the end of the flight once the physics said bye.  Until
  the newest reading's command has left, it runs in slices of :data:`SLICE_NS` of chip time (so
  the command is sent at once), then to the limit in one go;
* **latency compensation**: each reading is injected from the I/O tile at the cycle of its
  timestamp when the chip is not past it (whenever it arrived), else at the current cycle (counted
  late); a reading older than one already injected is dropped (counted stale: it would go back in
  time).  Readings repeated by the physics side for redundancy are dropped quietly; a reading
  outside the flight (after the scenario's duration, or numbered past its last sample) is dropped
  and counted (``outside``): believed, it would have the chip simulate until its time;
* the physics' silence is checked while the chip simulates as well as while it waits (``peer_timeout_s``);
  hellos go out every ``heartbeat_s``, never faster, whatever arrives meanwhile;
* each PWM command that reaches the I/O tile is sent at once with the chip time it arrived, plus
  the ``resend`` commands before it; on reaching its limit the chip sends its time (a command
  datagram, so the physics side knows every earlier command is out) and repeats it every
  ``heartbeat_s`` while it waits;
* the firmware's telemetry (its project's ``[[telemetry]]``, the estimate among it), read at each
  sample period's close as lockstep reads it (a host read: no simulated cycle), goes out at once
  in a telemetry datagram: the newest value of every name the hello announced, plus the
  ``resend`` entries before.

The counters and energy of the run are those of the replay harness: per-job records, charged to
the sample period they were released in (:meth:`FirmwareRun.close_period` at each injection).
"""

from __future__ import annotations

import contextlib
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from robosoc.chip.mpsoc import ChipError
from robosoc.chip.single import CoreError
from robosoc.config.link import LinkConfig
from robosoc.config.project import PROJECT_FILE
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.cosim.datagram import (
    MAX_COMMANDS,
    MAX_DATAGRAM_BYTES,
    Bye,
    ByeReason,
    Command,
    CommandBatch,
    Hello,
    Reading,
    SensorBatch,
    TelemetryBatch,
    TelemetryEntry,
    encode,
    max_telemetry_entries,
)
from robosoc.cosim.decoupled_physics import Ended, scenario_digest
from robosoc.cosim.firmware_run import DEFAULT_FIRST_CYCLE, FirmwareRun, ReplayResult
from robosoc.cosim.link import Address, ChipTransport, LinkLog, UdpLink
from robosoc.host.scenario_image import scenario_image
from robosoc.host.telemetry import TelemetryError
from robosoc.physics.clock import NS_PER_S, FlightClock
from robosoc.records import SampleInput

__all__ = ["SLICE_NS", "ChipOutcome", "serve_chip"]

#: Chip time run at a time while a command is due: it is sent at most this late (in chip time).
SLICE_NS = 250_000


@dataclass
class ChipOutcome:
    """What the chip side did: the firmware run's result, how it ended, the link's counts."""

    result: ReplayResult | None
    ended: str
    message: str
    host_s: float
    cpu_s: float
    simulated_s: float
    link: dict[str, object] = field(default_factory=dict)
    readings: dict[str, int] = field(default_factory=dict)

    @property
    def complete(self) -> bool:
        return self.ended == Ended.DONE


class _PeerSilent(Exception):
    pass


class _Chip:
    """State of the chip side during a flight (the helpers of :func:`serve_chip`)."""

    def __init__(
        self,
        run: FirmwareRun,
        link: ChipTransport,
        config: LinkConfig,
        period_ns: int,
        log: LinkLog,
        samples: int,
        on_period: Callable[[FirmwareRun], None] | None = None,
    ) -> None:
        self.run, self.link, self.config, self.period_ns, self.log = run, link, config, period_ns, log
        self.on_period = on_period
        self.samples = samples  # the physics sends readings 0 .. samples-1, at k * period_ns
        self.flight_ns = samples * period_ns  # the flight's end: no reading, and no bye's end, lies past it
        self.first = run.first_cycle
        self.clock_ns = run.clock_ns
        self.pending: dict[int, Reading] = {}
        self.seen: set[int] = set()  # every reading number received
        self.newest_k = -1
        self.newest_t: int | None = None
        self.end_ns: int | None = None
        self.peer_bye: Bye | None = None
        self.counts = {"received": 0, "injected": 0, "late": 0, "stale": 0, "repeated": 0, "outside": 0}
        self.recent: deque[Command] = deque(maxlen=min(MAX_COMMANDS, config.resend + 16))
        self.commands_sent = 0
        #: the firmware's telemetry names, in its project's order: the values of each entry sent
        self.names = tuple(probe.name for probe in run.image.telemetry)
        self.telemetry_read = 0  # of run.telemetry, sent
        self.published: dict[str, float] = {}  # the newest value of each telemetry name read so far
        most = max_telemetry_entries(len(self.names))
        self.recent_telemetry: deque[TelemetryEntry] = deque(maxlen=max(1, min(most, config.resend + 1)))
        self.last_send = time.monotonic()
        self.reported_ns = -1

    def cycle_of(self, t_ns: int) -> int:
        return self.first + round(t_ns / self.clock_ns)

    def now_ns(self) -> int:
        return math.floor((self.run.cycle - self.first) * self.clock_ns)

    def take(self, timeout: float) -> bool:
        got = self.link.receive(timeout)
        for d in got:
            body = d.body
            if isinstance(body, SensorBatch):
                for r in body.readings:
                    if r.t_ns >= self.flight_ns or r.k >= self.samples:
                        self.counts["outside"] += 1  # believed, it would make the chip simulate until then
                        self.log.write(
                            f"reading {r.k} (t={r.t_ns} ns) dropped: outside the flight "
                            f"({self.samples} readings, {self.flight_ns} ns)",
                            "outside the flight",
                        )
                        continue
                    if r.k in self.seen:
                        self.counts["repeated"] += 1
                        continue
                    self.seen.add(r.k)
                    self.counts["received"] += 1
                    if r.k < self.newest_k:
                        self.counts["stale"] += 1
                        self.log.write(
                            f"reading {r.k} dropped: older than reading {self.newest_k}, injected", "stale reading"
                        )
                    else:
                        self.pending[r.k] = r
            elif isinstance(body, Bye):
                self.peer_bye = body
                self.end_ns = min(body.end_ns, self.flight_ns)  # a bye cannot extend the flight
        return bool(got)

    def check_peer(self) -> None:
        """End (:class:`_PeerSilent`) once the physics has been silent for ``peer_timeout_s``:
        checked while the chip simulates too, not only while it waits."""
        silent = self.link.silent_for(time.monotonic())
        if silent > self.config.peer_timeout_s:
            raise _PeerSilent(
                f"no datagram from the physics for {silent:.1f} s (--peer-timeout {self.config.peer_timeout_s:g})"
            )

    def send(self, fresh: int) -> None:
        """A command datagram: the chip's time and the newest ``fresh + resend`` commands."""
        keep = min(len(self.recent), fresh + self.config.resend)
        commands = tuple(self.recent)[len(self.recent) - keep :]
        self.link.send_data(CommandBatch(self.now_ns(), commands))
        self.last_send = time.monotonic()
        self.reported_ns = self.now_ns()

    def send_telemetry(self) -> None:
        """Send the telemetry read since the last call (with the ``resend`` entries before): the
        physics' flight log has the firmware's values, its estimate among them, as lockstep's."""
        fresh = []
        for read in self.run.telemetry[self.telemetry_read :]:
            self.published.update(read.values)
            if 0 <= read.sample < len(self.run.samples):
                s = self.run.samples[read.sample]
                values = tuple(self.published.get(name, math.nan) for name in self.names)
                fresh.append(TelemetryEntry(s.seq & 0xFFFFFFFF, round(s.time_s * NS_PER_S), values))
        self.telemetry_read = len(self.run.telemetry)
        if fresh:
            self.recent_telemetry.extend(fresh)
            self.link.send_data(TelemetryBatch(self.now_ns(), tuple(self.recent_telemetry)))

    def inject_due(self) -> bool:
        """Inject the oldest waiting reading if the chip has reached its cycle; whether it did."""
        if not self.pending:
            return False
        k = min(self.pending)
        r = self.pending[k]
        cycle = self.cycle_of(r.t_ns)
        if cycle > self.run.cycle:
            return False
        del self.pending[k]
        if cycle < self.run.cycle:
            self.counts["late"] += 1
            self.log.write(
                f"reading {k} (t={r.t_ns} ns) injected late, at chip time {self.now_ns()} ns", "late reading"
            )
            cycle = self.run.cycle
        if self.run.samples:
            self.run.close_period()
            self.send_telemetry()
            if self.on_period is not None:
                self.on_period(self.run)
        self.run.inject(SampleInput(k, r.t_ns / NS_PER_S, cycle, r.packet))
        self.counts["injected"] += 1
        self.newest_k, self.newest_t = k, r.t_ns
        return True

    def limit(self) -> int:
        """The cycle the chip may run to now."""
        if self.pending:
            return self.cycle_of(self.pending[min(self.pending)].t_ns)
        if self.end_ns is not None:
            return self.cycle_of(self.end_ns)
        if self.newest_t is not None:
            return self.cycle_of(self.newest_t + self.period_ns)
        return self.cycle_of(0)

    def advance(self, limit: int) -> None:
        """Run towards ``limit``: in slices while the newest reading's command has not left (so that
        it leaves at once), then in one go (nothing can arrive that the chip could use before)."""
        answered = bool(self.recent) and self.recent[-1].seq >= (self.newest_k & 0xFFFFFFFF)
        if not answered:
            limit = min(limit, self.run.cycle + max(1, round(SLICE_NS / self.clock_ns)))
        fresh = self.run.run_to(limit)
        for c in fresh:
            left = math.floor((c.cycle - self.first) * self.clock_ns)
            self.recent.append(Command(c.seq & 0xFFFFFFFF, max(0, left), c.pwm))
        self.commands_sent += len(fresh)
        if fresh:
            self.send(len(fresh))

    def wait(self) -> None:
        """At the limit with nothing to inject: report the chip's time, wait, repeat it now and then."""
        if self.reported_ns != self.now_ns() or time.monotonic() - self.last_send >= self.config.heartbeat_s:
            self.send(0)
        self.take(self.config.heartbeat_s)
        self.check_peer()


def _check_telemetry_fits(run: FirmwareRun, project_file: Path, period_ns: int) -> None:
    """Refuse a project whose telemetry names do not fit the hello or whose values do not fit one
    telemetry datagram (:class:`TelemetryError`, a build error naming the project file)."""
    names = tuple(probe.name for probe in run.image.telemetry)
    try:
        encode(Hello(bytes(8), period_ns, names))
        fits = max_telemetry_entries(len(names)) >= 1
    except ValueError:
        fits = False
    if not fits:
        raise TelemetryError(
            str(project_file), "telemetry",
            f"{len(names)} values named in {sum(map(len, names))} bytes do not fit a datagram of the decoupled "
            f"mode ({MAX_DATAGRAM_BYTES} bytes: the names in the hello, each entry's values 8 bytes each)",
        )  # fmt: skip


def serve_chip(
    scenario: ScenarioConfig,
    vehicle: VehicleConfig,
    config: LinkConfig,
    peer: Address | str,
    bind: Address | None = None,
    *,
    log_path: Path | None = None,
    on_status: Callable[[str], None] | None = None,
    transport: Callable[[LinkLog], ChipTransport] | None = None,
    on_period: Callable[[FirmwareRun], None] | None = None,
) -> ChipOutcome:
    """Run the scenario's firmware on its chip for the physics side at ``peer``; see the module docstring.

    Args:
        scenario, vehicle: what the physics side flies (the firmware's control parameters come
            from them; the physics side refuses a chip built for another); the scenario's seed
            drives the faults injected on the command datagrams.
        config: timeouts, redundancy and faults (pace and hold are the physics side's).
        peer: the physics side's address (or, with ``transport``, how to name it).
        bind: where to listen (default: any free port on the loopback interface of ``peer``'s family).
        log_path: the side's link log (``link-chip.log``), or None.
        on_status: told what the side is doing (building, booting, waiting, flying).
        transport: makes the link to the physics from the side's log instead of a UDP socket
            (the ROS 1 node's, :mod:`robosoc.cosim.ros_chip`).
        on_period: called with the firmware run at each sample period's close (its telemetry and
            jobs so far are there).

    Returns:
        The outcome, also when interrupted (Ctrl-C), the physics went silent or said bye early, or
        the firmware faulted (``ended`` says which; the result holds the jobs up to then).

    Raises:
        LinkError: ``bind`` cannot be bound or ``peer`` resolved.
        ValueError: the mapping does not fit the chip.
        CompileError: the firmware failed to build.
        TelemetryError: the project declares more telemetry values than a datagram holds.
    """
    say = on_status or (lambda _text: None)
    period_ns = FlightClock.of(scenario).sample_period_ns
    log = LinkLog(log_path)
    link: ChipTransport
    try:
        if transport is not None:
            link = transport(log)
        else:
            assert isinstance(peer, Address)
            if bind is None:
                bind = Address("::1" if ":" in peer.host else "127.0.0.1", 0)
                if peer.host not in ("127.0.0.1", "::1", "localhost"):
                    bind = Address("::" if ":" in peer.host else "0.0.0.0", 0)
            link = UdpLink(bind, "chip", config.faults, scenario.seed, log, peer=peer)
    except BaseException:
        log.close()
        raise
    start = time.monotonic()
    cpu_start = time.process_time()
    state: _Chip | None = None
    run: FirmwareRun | None = None
    result: ReplayResult | None = None
    ended, message = Ended.DONE, "flown"
    try:
        fw = scenario.firmware
        say(f"building the firmware ({fw.label}) and loading the chip ...")
        run = FirmwareRun(fw, scenario_image(scenario, vehicle), chip=scenario.chip, first_cycle=DEFAULT_FIRST_CYCLE)
        _check_telemetry_fits(run, fw.project_folder / PROJECT_FILE, period_ns)
        say("booting the chip (compiling the chip kernels on a fresh install) ...")
        run.run_to(DEFAULT_FIRST_CYCLE)
        if on_period is not None:
            on_period(run)  # booted: nothing estimated yet
        samples = round(scenario.duration_s * scenario.sensors.rate_hz)  # as the physics side counts them
        state = _Chip(run, link, config, period_ns, log, samples, on_period)
        say(f"waiting for the physics at {peer} ...")
        hello = Hello(scenario_digest(scenario, vehicle), period_ns, state.names)
        deadline = time.monotonic() + config.connect_timeout_s
        last_hello = -math.inf
        while not state.pending and state.end_ns is None:
            now = time.monotonic()
            if now - last_hello >= config.heartbeat_s:  # every heartbeat, however much garbage arrives
                link.send_control(hello)
                last_hello = now
            state.take(max(0.0, last_hello + config.heartbeat_s - time.monotonic()))
            if time.monotonic() > deadline:
                raise _PeerSilent(
                    f"no sensor data from the physics at {peer} within --connect-timeout {config.connect_timeout_s:g} s"
                )
        say("flying")
        start = time.monotonic()
        cpu_start = time.process_time()
        while True:
            state.take(0.0)
            if state.end_ns is None:
                state.check_peer()
            if state.peer_bye is not None and state.peer_bye.reason is not ByeReason.DONE:
                ended, message = Ended.PEER_ENDED, f"the physics said bye ({state.peer_bye.reason.name.lower()})"
                break
            if state.inject_due():
                continue
            limit = state.limit()
            if run.cycle < limit:
                state.advance(limit)
            elif state.end_ns is not None and not state.pending:
                break  # at the end of the flight
            else:
                state.wait()
    except KeyboardInterrupt:
        ended, message = Ended.INTERRUPTED, "interrupted"
    except _PeerSilent as exc:
        ended, message = Ended.PEER_LOST, str(exc)
    except (ChipError, CoreError) as exc:
        ended, message = Ended.FAILED, f"the firmware failed on the chip: {exc}"
    finally:
        host_s = time.monotonic() - start
        cpu_s = time.process_time() - cpu_start
        log.write(f"ended: {ended}: {message}")
        try:
            if run is not None and run.samples:
                run.close_period()
            result = run.result() if run is not None else None
        except (ChipError, CoreError, RuntimeError, KeyboardInterrupt) as exc:
            log.write(f"no job records: {exc}")
        reason = {
            Ended.DONE: ByeReason.DONE,
            Ended.INTERRUPTED: ByeReason.INTERRUPTED,
            Ended.PEER_LOST: ByeReason.PEER_LOST,
        }.get(ended, ByeReason.ERROR)
        end_ns = state.now_ns() if state is not None else 0
        with contextlib.suppress(KeyboardInterrupt):
            link.send_control(Bye(reason, link.sent, end_ns))
        link.close()
        readings = dict(state.counts) if state is not None else {}
        if state is not None:
            readings["commands_sent"] = state.commands_sent
        outcome = ChipOutcome(
            result=result,
            ended=ended,
            message=message,
            host_s=host_s,
            cpu_s=cpu_s,
            simulated_s=end_ns / NS_PER_S,
            link=link.report(),
            readings=readings,
        )
        log.write(f"counts: {outcome.link}; readings {readings}")
        log.close()
    return outcome
