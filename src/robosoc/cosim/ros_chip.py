"""The chip as a ROS 1 node (``robosoc serve chip --ros``): hector's sensor topics in, PWM out.

The node is the decoupled mode's chip side (:func:`robosoc.cosim.decoupled_chip.serve_chip`: pacing,
latency compensation, counts, logs) with ROS topics instead of UDP datagrams
(:class:`RosChipLink`; topics: :mod:`robosoc.cosim.ros_topics`, docs/ros.md):

* **a sensor sample per** ``raw_imu`` **message**: its gyro and specific force, with the newest
  ``magnetic`` and ``pressure_height`` readings stamped at or before it.  A hector world publishes
  those at lower rates (10 Hz); robosoc's physics node at the IMU's.  The node learns each one's
  period from its stamps and waits for a reading that is due (stamped at or before the IMU's by its
  period) before it builds the sample -- so which readings a sample holds does not depend on which
  topic's message happened to arrive first -- but no longer than :data:`AUX_WAIT_S` (then it takes
  the newest it has, counted ``held``);
* **time**: the first ``raw_imu`` stamp is the flight's time 0; each sample is injected at the
  chip cycle of its stamp, its setpoint is the scenario's flight plan at that time (a hector world
  has no robosoc flight plan; the chip flies the scenario's), its sample number ``k`` is its time
  in sensor periods, rounded;
* **bad input, counted per topic** (``chip.json`` ``"link"``): a message stamped before the newest
  one of its topic (``out_of_order``, dropped), at the same stamp (``duplicate``, dropped); an IMU
  message whose interval from the previous one is off the scenario's sensor period by more than a
  quarter (``off_rate``, used) or that falls on a sample number already used (``extra``, dropped);
  a message stamped after the flight's end (``outside``, dropped);
* **out**: each PWM command on ``motor_pwm`` (``hector_uav_msgs/MotorPWM``) stamped with the chip
  time it reached the I/O tile; ``chip/status`` (``robosoc_msgs/ChipStatus``: how far the chip has
  simulated and how many commands and telemetry messages it has published by then; the physics
  node paces on it); the firmware's telemetry (its project's ``[[telemetry]]``, read at each sample
  period's close, no simulated cycle) on ``chip/telemetry`` (``robosoc_msgs/Telemetry``: every
  name, stamped with the sample; the physics node logs it) and each value under a name of its own
  on ``telemetry/NAME`` (``std_msgs/Float64``); the estimate among it on ``chip/estimate``; each
  job's response time on ``chip/response_time/TASK`` at each sample period's close.

:func:`check_topics` refuses, before the chip is built, a ROS graph in which a sensor topic is
published with another type, or in which the vehicle's namespace has no ``raw_imu`` while other
namespaces have (the namespace does not exist).
"""

from __future__ import annotations

import math
import time
from collections import deque
from typing import Any

import numpy as np

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.setpoint import setpoint_at
from robosoc.cosim.datagram import (
    Bye,
    ByeReason,
    CommandBatch,
    Datagram,
    Hello,
    Kind,
    Reading,
    SensorBatch,
    TelemetryBatch,
)
from robosoc.cosim.firmware_run import FirmwareRun
from robosoc.cosim.link import LinkLog
from robosoc.cosim.replay import sensor_packet
from robosoc.cosim.ros1 import Node, RosUnavailable, full_name, stamp_ns, to_time
from robosoc.cosim.ros_topics import FRAME_BODY, FRAME_WORLD, SENSOR_TOPICS, topic
from robosoc.host.telemetry import ESTIMATE_NAMES, estimate_of, own_columns
from robosoc.physics.clock import NS_PER_S, FlightClock

__all__ = ["AUX_WAIT_S", "NAMESPACE_GRACE_S", "RosChipLink", "check_topics"]

AUX_WAIT_S = 0.5
"""Longest wait (wall clock) for a magnetic or pressure reading that is due before a sample is built."""
NAMESPACE_GRACE_S = 3.0
"""How long the node waits for its namespace's ``raw_imu`` when other namespaces have one."""

_COL = {name: i for i, name in enumerate(ROW_FIELDS)}


def check_topics(node: Node, namespace: str, timeout_s: float) -> None:
    """Wait (up to ``timeout_s``) until ``NAMESPACE/raw_imu`` is published; refuse a sensor topic or
    ``motor_pwm`` of another type at once, and a namespace that does not exist after
    :data:`NAMESPACE_GRACE_S` (other namespaces publish ``raw_imu``, this one does not).

    Raises:
        RosUnavailable: the message names the topic, the types, or the namespaces there are.
    """
    imu = full_name(namespace, topic("imu").name)
    start = time.monotonic()
    others_since: float | None = None
    while True:
        types = node.published_types()
        for key in (*SENSOR_TOPICS, "motor_pwm"):
            t = topic(key)
            name = full_name(namespace, t.name)
            if name in types and types[name] != t.type:
                raise RosUnavailable(f"{name} is published as {types[name]}, expected {t.type}")
        if imu in types:
            return
        now = time.monotonic()
        others = sorted(n for n in types if n.endswith("/" + topic("imu").name))
        if others and others_since is None:
            others_since = now
        if others and others_since is not None and now - others_since > NAMESPACE_GRACE_S:
            spaces = ", ".join(n[: -len(topic("imu").name) - 1] or "/" for n in others)
            raise RosUnavailable(
                f"--ns {namespace}: no vehicle there (nothing publishes {imu}); vehicles publishing raw_imu: {spaces}"
            )
        if now - start > timeout_s:
            raise RosUnavailable(
                f"nothing publishes {imu} within --connect-timeout {timeout_s:g} s (is the physics up?)"
            )
        time.sleep(0.1)


class _Aux:
    """The readings of one auxiliary sensor topic (magnetic, pressure height) by stamp."""

    def __init__(self) -> None:
        self.readings: deque[tuple[int, tuple[float, ...]]] = deque()

    def used(self, stamp: int) -> None:
        """A sample at ``stamp`` has been built: forget the readings no later sample can use."""
        while len(self.readings) >= 2 and self.readings[1][0] <= stamp:
            self.readings.popleft()

    def ready(self, stamp: int) -> bool:
        """Whether the reading for a sample at ``stamp`` is known: one at or after it came, or the
        next one (by the topic's period, from its last two stamps) is not due by then."""
        if not self.readings:
            return False
        newest = self.readings[-1][0]
        if newest >= stamp:
            return True
        if len(self.readings) >= 2:
            period = newest - self.readings[-2][0]
            return newest + period > stamp
        return False

    def at(self, stamp: int) -> tuple[float, ...] | None:
        """The newest reading stamped at or before ``stamp`` (else the oldest known, or None)."""
        best = None
        for s, value in self.readings:
            if s <= stamp:
                best = value
        if best is None and self.readings:
            return self.readings[0][1]
        return best


#: the most a chip node waits, after its flight, for its last messages to leave (RosChipLink.close)
LINGER_S = 1.0


class RosChipLink:
    """The chip side's link to the physics through ROS 1 topics (a
    :class:`robosoc.cosim.link.ChipTransport`); see the module docstring."""

    def __init__(
        self, node: Node, scenario: ScenarioConfig, vehicle: VehicleConfig, namespace: str, log: LinkLog, digest: bytes
    ) -> None:
        self.node, self.scenario, self.vehicle, self.log = node, scenario, vehicle, log
        self.namespace = namespace
        self.digest = digest.hex()
        clock = FlightClock.of(scenario)
        self.period_ns = clock.sample_period_ns
        self.samples = clock.sample_count
        self.flight_ns = clock.duration_ns
        self.names = {key: full_name(namespace, topic(key).name) for key in (*SENSOR_TOPICS, "motor_pwm", "status")}
        for key in SENSOR_TOPICS:
            node.subscribe(self.names[key], topic(key).type, (namespace, key))
        self.pwm_pub = node.publisher(self.names["motor_pwm"], topic("motor_pwm").type)
        self.status_pub = node.publisher(self.names["status"], topic("status").type, latch=True)
        self.estimate_pub = node.publisher(full_name(namespace, topic("estimate").name), topic("estimate").type)
        self.telemetry_pub = node.publisher(full_name(namespace, topic("telemetry").name), topic("telemetry").type)
        self.value_pubs: dict[str, Any] = {}  # telemetry/NAME, advertised with the hello (the names are its)
        self.telemetry_names: tuple[str, ...] = ()
        self.telemetry_sent = 0  # chip/telemetry messages published
        self.telemetry_k = -1
        self.response_pubs: dict[str, Any] = {}
        self.pwm_class = self.pwm_pub.data_class
        self.status_class = self.status_pub.data_class
        self.estimate_class = self.estimate_pub.data_class
        self.t0: int | None = None  # ROS time [ns] of the flight's time 0: the first raw_imu stamp
        self.waiting: deque[tuple[int, Any, float]] = deque()  # raw_imu messages not yet built: (stamp, msg, arrival)
        self.aux = {key: _Aux() for key in SENSOR_TOPICS if key != "imu"}
        self.newest: dict[str, int] = {}
        self.counts: dict[str, dict[str, int]] = {
            key: {"received": 0, "out_of_order": 0, "duplicate": 0} for key in SENSOR_TOPICS
        }
        self.counts["imu"].update({"off_rate": 0, "extra": 0, "outside": 0, "held": 0})
        self.last_k = -1
        self.last_imu: int | None = None
        self.readings = 0
        self.last_heard: float | None = None
        self.sent = 0  # motor_pwm messages published
        self.status_sent = 0
        self.published_seq = -1
        self.said_bye = False
        self.jobs_seen = 0

    # --- in ---------------------------------------------------------------------------------------

    def receive(self, timeout: float) -> list[Datagram]:
        deadline = time.monotonic() + max(0.0, timeout)
        while True:
            for arrival in self.node.take(max(0.0, deadline - time.monotonic())):
                self._arrive(arrival.key[1], arrival.message, arrival.at)
            out = self._build()
            if out or time.monotonic() >= deadline:
                return out

    def _arrive(self, key: str, message: Any, at: float) -> None:
        self.last_heard = at
        stamp = stamp_ns(message.header.stamp)
        counts = self.counts[key]
        counts["received"] += 1
        newest = self.newest.get(key)
        if newest is not None and stamp <= newest:
            kind = "duplicate" if stamp == newest else "out_of_order"
            counts[kind] += 1
            self.log.write(f"{self.names[key]}: message stamped {stamp} ns dropped ({kind}; newest {newest} ns)", kind)
            return
        self.newest[key] = stamp
        if key == "imu":
            if self.last_imu is not None and abs(stamp - self.last_imu - self.period_ns) * 4 > self.period_ns:
                counts["off_rate"] += 1
                self.log.write(
                    f"{self.names[key]}: {(stamp - self.last_imu) / 1e6:g} ms after the previous message, "
                    f"not the scenario's {self.period_ns / 1e6:g} ms",
                    "off rate",
                )
            self.last_imu = stamp
            if self.t0 is None:
                self.t0 = stamp
                self.log.write(f"flight time 0 is {self.names[key]}'s first stamp, {stamp} ns")
            self.waiting.append((stamp, message, at))
        elif key == "magnetic":
            v = message.vector
            self.aux[key].readings.append((stamp, (v.x, v.y, v.z)))
        else:
            self.aux[key].readings.append((stamp, (message.point.z,)))

    def _build(self) -> list[Datagram]:
        """The samples whose auxiliary readings are known, as sensor batches (and a bye after the last)."""
        out: list[Datagram] = []
        while self.waiting:
            stamp, message, at = self.waiting[0]
            late = time.monotonic() - at > AUX_WAIT_S
            if not all(aux.ready(stamp) for aux in self.aux.values()):
                if not late or any(aux.at(stamp) is None for aux in self.aux.values()):
                    break
                self.counts["imu"]["held"] += 1
                self.log.write(f"sample at {stamp} ns built with the newest magnetic/pressure readings", "held")
            self.waiting.popleft()
            for aux in self.aux.values():
                aux.used(stamp)
            assert self.t0 is not None
            t_ns = stamp - self.t0
            if t_ns >= self.flight_ns:
                self.counts["imu"]["outside"] += 1
                self.log.write(f"raw_imu at flight time {t_ns} ns dropped: after the flight's end", "outside")
                continue
            k = round(t_ns / self.period_ns)
            if k <= self.last_k:
                self.counts["imu"]["extra"] += 1
                self.log.write(f"raw_imu at flight time {t_ns} ns dropped: sample {k} has one", "extra")
                continue
            self.last_k = k
            reading = self._reading(k, t_ns, stamp, message)
            out.append(Datagram(Kind.SENSORS, self.readings, SensorBatch(t_ns, (reading,))))
            self.readings += 1
            if k >= self.samples - 1:
                out.append(Datagram(Kind.BYE, 0, Bye(ByeReason.DONE, self.readings, self.flight_ns)))
                self.waiting.clear()
                break
        return out

    def _reading(self, k: int, t_ns: int, stamp: int, imu: Any) -> Reading:
        row = np.zeros(len(ROW_FIELDS))
        t = t_ns / NS_PER_S
        sp = setpoint_at(self.scenario.flight, self.vehicle.rest_height, t)
        values = {
            "t": t,
            "armed": float(sp.armed),
            "sp_roll": sp.roll,
            "sp_pitch": sp.pitch,
            "sp_yaw": sp.yaw,
            "sp_height": sp.height,
            "sp_height_rate": sp.height_rate,
            "sp_height_accel": sp.height_accel,
        }
        w, a = imu.angular_velocity, imu.linear_acceleration
        values.update(gyro_x=w.x, gyro_y=w.y, gyro_z=w.z, accel_x=a.x, accel_y=a.y, accel_z=a.z)
        mag = self.aux["magnetic"].at(stamp) or (0.0, 0.0, 0.0)
        values.update(mag_x=mag[0], mag_y=mag[1], mag_z=mag[2])
        values["baro_altitude"] = (self.aux["pressure_height"].at(stamp) or (0.0,))[0]
        for name, value in values.items():
            row[_COL[name]] = value
        return Reading(k, t_ns, sensor_packet(row, k, self.period_ns // 1000))

    def silent_for(self, now: float) -> float:
        return now - self.last_heard if self.last_heard is not None else 0.0

    # --- out --------------------------------------------------------------------------------------

    def _ros_time(self, t_ns: int) -> Any:
        return to_time((self.t0 or 0) + t_ns)

    def send_data(self, body: CommandBatch | TelemetryBatch) -> None:
        if isinstance(body, TelemetryBatch):
            self._telemetry(body)
            return
        for c in body.commands:
            if self.published_seq >= 0 and c.seq <= self.published_seq:
                continue  # a command repeated for the UDP link's redundancy: TCP needs none
            self.published_seq = c.seq
            msg = self.pwm_class()
            msg.header.stamp = self._ros_time(c.left_ns)
            msg.header.frame_id = FRAME_BODY
            msg.pwm = bytes(c.pwm)
            self.pwm_pub.publish(msg)
            self.sent += 1
        self._status(body.chip_now_ns)

    def _status(self, chip_ns: int) -> None:
        msg = self.status_class()
        msg.header.stamp = self._ros_time(chip_ns) if self.t0 is not None else to_time(0)
        msg.commands = self.sent
        msg.telemetry = self.telemetry_sent
        msg.scenario = self.digest
        self.status_pub.publish(msg)
        self.status_sent += 1

    def send_control(self, body: Hello | Bye) -> None:
        if isinstance(body, Hello):
            if body.telemetry != self.telemetry_names:
                self.telemetry_names = body.telemetry
                for name in own_columns(body.telemetry):
                    key = full_name(self.namespace, topic("telemetry_value").name.format(name=name))
                    self.value_pubs[name] = self.node.publisher(key, topic("telemetry_value").type)
            self._status(0)
        else:
            self.said_bye = True
            self._status(body.end_ns)

    def _telemetry(self, body: TelemetryBatch) -> None:
        """Each new entry on chip/telemetry, its own-name values on telemetry/NAME, its estimate
        (if the project publishes one) on chip/estimate."""
        estimates = any(n in ESTIMATE_NAMES for n in self.telemetry_names)
        for e in body.entries:
            if e.k <= self.telemetry_k:
                continue  # repeated for the UDP link's redundancy
            self.telemetry_k = e.k
            stamp = self._ros_time(e.t_ns)  # the sample it includes
            msg = self.telemetry_pub.data_class()
            msg.header.stamp, msg.header.frame_id = stamp, FRAME_BODY
            msg.sample, msg.names, msg.values = e.k, list(self.telemetry_names), list(e.values)
            self.telemetry_pub.publish(msg)
            self.telemetry_sent += 1
            values = dict(zip(self.telemetry_names, e.values, strict=True))
            for name, pub in self.value_pubs.items():
                if not math.isnan(values[name]):
                    pub.publish(pub.data_class(data=values[name]))
            if estimates:
                self._estimate(stamp, values)

    def _estimate(self, stamp: Any, values: dict[str, float]) -> None:
        e = estimate_of(values)
        msg = self.estimate_class()
        msg.header.stamp = stamp
        msg.header.frame_id = FRAME_WORLD
        msg.pose.position.x = msg.pose.position.y = math.nan
        msg.pose.position.z = e.height
        w, x, y, z = (float(v) for v in e.quaternion)
        msg.pose.orientation.w, msg.pose.orientation.x = w, x
        msg.pose.orientation.y, msg.pose.orientation.z = y, z
        self.estimate_pub.publish(msg)

    def period_closed(self, run: FirmwareRun) -> None:
        """Publish the job response times the chip has produced since the last call (the first
        call, at boot, advertises a topic per task)."""
        for task in sorted(set(run.names.values())):
            self._response_pub(task)
        jobs = run.jobs_logged(self.jobs_seen)
        self.jobs_seen += len(jobs)
        for task, release, completion in jobs:
            pub = self._response_pub(task)
            pub.publish(pub.data_class(data=(completion - release) * run.clock_ns / 1000.0))

    def _response_pub(self, task: str) -> Any:
        pub = self.response_pubs.get(task)
        if pub is None:
            name = full_name(self.namespace, topic("response_time").name.format(task=task))
            pub = self.response_pubs[task] = self.node.publisher(name, topic("response_time").type)
        return pub

    def report(self) -> dict[str, object]:
        return {
            "to_physics": {
                "sent": self.sent,
                "status_sent": self.status_sent,
                "telemetry_sent": self.telemetry_sent,
                "transport": "ros1",
            },
            "from_physics": {key: dict(c) for key, c in self.counts.items()},
        }

    def close(self) -> None:
        """Close the node's topics; after a flight that ended normally, first wait (at most
        :data:`LINGER_S`) until nothing subscribes to ``chip/status`` any more.  rospy publishes from
        a thread per connection, and closing at once could drop the last status, which the physics
        node waits for: it then ended, the flight all but done, with "nothing from the chip" after
        ``--peer-timeout`` (once in a CI run of two vehicles).  The physics node closes its
        subscription when it has all it needs; a recorder or a viewer may stay subscribed, hence
        the bound."""
        deadline = time.monotonic() + LINGER_S
        while self.said_bye and self.status_pub.get_num_connections() > 0 and time.monotonic() < deadline:
            time.sleep(0.02)
        self.node.close()
