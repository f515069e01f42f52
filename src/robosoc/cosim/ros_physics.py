"""robosoc's physics as a ROS 1 node (``robosoc serve physics --ros``), publishing as hector's plugins do.

One world with the scenario's vehicles, each under its namespace (:func:`vehicle_namespace`:
``/`` for one, ``/uav1``, ``/uav2`` ... for several), each flown by a chip node in that namespace
(:mod:`robosoc.cosim.ros_chip`).  Per sensor sample ``k`` (flight time ``t_k``, ROS time
:data:`START_NS` + ``t_k``):

1. ``/clock`` is set to ``t_k``; each vehicle's ``raw_imu``, ``magnetic``, ``pressure_height``,
   ``altimeter`` and ``ground_truth/state`` are published stamped ``t_k``, and ``/tf`` with every
   vehicle's true pose (``world`` -> ``NS/base_link``, hector's tf_prefix);
2. the node waits until the period's physics steps may be taken -- ``pace="realtime"``: the wall
   clock has reached ``t_k+1`` since the start; ``pace="fast"`` (simulated time: a slow host changes
   nothing): every chip's ``chip/status`` says it has simulated past ``t_k+1`` and every
   ``motor_pwm`` and ``chip/telemetry`` message it counts there has come -- taking the commands
   and the telemetry meanwhile;
3. each command applies from the physics step of its stamp or, if it came later (realtime), from
   the step it came in (counted late), held as :class:`~robosoc.cosim.actuator_hold.ActuatorHold`
   says; the world takes the period's steps.  Row k shows the chip's newest telemetry of a sample
   before k (:class:`~robosoc.cosim.telemetry_rows.TelemetryRows`, as the UDP physics side): the
   estimate columns and the project's own telemetry columns of ``flight.csv``.

Before the first sample it waits (``connect_timeout_s``) for every vehicle's chip: its status
(which names the scenario its firmware was built for: another is refused) and every subscription
connected both ways (a message published before a connection exists is lost in ROS 1).  A chip
silent for ``peer_timeout_s`` ends the flight (its namespace is named).  ``use_sim_time`` is set on
the parameter server, for the nodes started after this one (rosbag, rqt).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robosoc.config.link import LinkConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.control.flight import ROW_FIELDS, flight_row
from robosoc.control.setpoint import setpoint_at
from robosoc.cosim.actuator_hold import ActuatorHold
from robosoc.cosim.decoupled_physics import Ended, Mismatch, PeerSilent, PhysicsOutcome
from robosoc.cosim.link import LinkLog
from robosoc.cosim.lockstep import PWM_COLUMNS, UNKNOWN_ESTIMATE
from robosoc.cosim.ros1 import Node, full_name, message_class, stamp_ns, to_time
from robosoc.cosim.ros_topics import FRAME_BODY, FRAME_WORLD, SENSOR_TOPICS, topic, vehicle_namespace
from robosoc.cosim.telemetry_rows import TelemetryRows
from robosoc.physics import World
from robosoc.physics.clock import NS_PER_S, PHYSICS_STEP_NS, START_NS, FlightClock

__all__ = ["serve_physics_ros"]

PUBLISHED = ("imu", "magnetic", "pressure_height", "altimeter", "ground_truth")
QNH_HPA = 1013.25
"""hector's baro plugin's default QNH [hPa]."""


@dataclass
class _Vehicle:
    """One vehicle's topics and the state of its chip as the physics sees it."""

    index: int
    namespace: str
    hold: ActuatorHold
    log: LinkLog
    telemetry: TelemetryRows
    pubs: dict[str, Any] = field(default_factory=dict)
    subs: list[Any] = field(default_factory=list)
    frame: str = FRAME_BODY
    progress_ns: int = -1
    announced: int = 0  # commands the chip says it has published
    received: int = 0
    late: int = 0
    out_of_order: int = 0
    malformed: int = 0
    telemetry_announced: int = 0  # chip/telemetry messages the chip says it has published
    telemetry_arrived: int = 0
    telemetry_refused: int = 0  # not the project's names, or not a value per name
    told: list[tuple[float, ...]] = field(default_factory=list)  # each row's own telemetry values
    last_step: int = 0
    heard: float | None = None
    digest: str | None = None
    rows: list[np.ndarray] = field(default_factory=list)

    def name(self, key: str) -> str:
        return full_name(self.namespace, topic(key).name)


def serve_physics_ros(
    scenario: ScenarioConfig,
    vehicles: Sequence[VehicleConfig],
    digest: bytes,
    config: LinkConfig,
    *,
    telemetry: Sequence[str] = (),
    log_paths: Sequence[Any] | None = None,
    start_delay_s: float = 0.0,
    on_start: Callable[[], None] | None = None,
    on_row: Callable[[int, np.ndarray, tuple[float, ...]], None] | None = None,
    on_sample: Callable[[int, int], None] | None = None,
) -> list[PhysicsOutcome]:
    """Fly ``scenario`` with ``vehicles`` in one world, each flown by a chip node over ROS 1; see
    the module docstring.

    Args:
        digest: what the chips' firmware must have been built for
            (:func:`robosoc.cosim.decoupled_physics.scenario_digest` of the scenario and vehicle).
        config: pacing (``realtime`` or ``fast``), hold, timeouts.
        telemetry: the names of the telemetry values the chips' firmware publishes (its project's
            ``[[telemetry]]``, in order); a ``chip/telemetry`` message naming others is refused (counted).
        log_paths: each vehicle's log (``link-physics.log``), or None.
        start_delay_s: wall time between the chips' arrival and the first sample (time for a
            recorder such as ``rosbag record -a``, which looks for new topics once a second, to
            subscribe to every topic first).
        on_start: called when every chip is there and the flight starts.
        on_row: called with (vehicle index, row, its own telemetry values) as soon as a row is
            complete (the flight logs).
        on_sample: called with (samples done, samples in all).

    Returns:
        Each vehicle's outcome, also when the flight was interrupted (Ctrl-C) or a chip went silent.

    Raises:
        RosUnavailable: ROS is not installed, or no master answers.
    """
    clock = FlightClock.of(scenario)
    samples, period_ns = clock.sample_count, clock.sample_period_ns
    node = Node("robosoc_physics")
    node.set_param("/use_sim_time", True)
    world = World(list(vehicles), scenario.sensors, scenario.wind)
    world.reset(scenario.seed)
    quads = world.quadrotors
    fleet: list[_Vehicle] = []
    for i, quad in enumerate(quads):
        ns = vehicle_namespace(i, len(quads))
        log = LinkLog(log_paths[i] if log_paths is not None else None)
        v = _Vehicle(i, ns, ActuatorHold(config.hold, quad.pwm), log, TelemetryRows(telemetry))
        v.frame = full_name(ns, FRAME_BODY).lstrip("/")
        for key in PUBLISHED:
            v.pubs[key] = node.publisher(v.name(key), topic(key).type, queue_size=100)
        v.subs.append(node.subscribe(v.name("motor_pwm"), topic("motor_pwm").type, (i, "motor_pwm")))
        v.subs.append(node.subscribe(v.name("status"), topic("status").type, (i, "status")))
        if telemetry:
            v.subs.append(node.subscribe(v.name("telemetry"), topic("telemetry").type, (i, "telemetry")))
        log.write(f"physics: vehicle {i + 1} at {ns}; pace {config.pace}, hold {config.hold}")
        fleet.append(v)
    clock_pub = node.publisher(topic("clock").name, topic("clock").type, queue_size=10)
    tf_pub = node.publisher(topic("tf").name, topic("tf").type, queue_size=100)
    classes = {key: pub.data_class for key, pub in fleet[0].pubs.items()}
    classes["clock"], classes["tf"] = clock_pub.data_class, tf_pub.data_class
    transform_class = message_class("geometry_msgs/TransformStamped")
    expected = digest.hex()

    def publish_clock(t_ns: int) -> None:
        clock_pub.publish(classes["clock"](clock=to_time(START_NS + t_ns)))

    def take(timeout: float, first_step: int, last_step: int, start: float) -> None:
        for arrival in node.take(timeout):
            i, kind = arrival.key
            v = fleet[i]
            v.heard = arrival.at
            msg = arrival.message
            if kind == "status":
                v.progress_ns = max(v.progress_ns, stamp_ns(msg.header.stamp) - START_NS)
                v.announced = max(v.announced, int(msg.commands))
                v.telemetry_announced = max(v.telemetry_announced, int(msg.telemetry))
                if v.digest is None:
                    v.digest = str(msg.scenario)
                    if v.digest != expected:
                        raise Mismatch(
                            f"{v.namespace}: the chip's firmware was built for another scenario or vehicle "
                            "(give both nodes the same scenario options)"
                        )
                continue
            if kind == "telemetry":
                v.telemetry_arrived += 1
                names = tuple(msg.names)
                if names != v.telemetry.names or not v.telemetry.arrive(int(msg.sample), msg.values):
                    v.telemetry_refused += 1
                    v.log.write(
                        f"{v.name('telemetry')}: sample {msg.sample} refused: {len(msg.values)} values named "
                        f"({', '.join(names)}), the project declares ({', '.join(v.telemetry.names)})",
                        "telemetry refused",
                    )
                continue
            v.received += 1
            pwm = bytes(msg.pwm) if not isinstance(msg.pwm, bytes) else msg.pwm
            if len(pwm) < 4:
                v.malformed += 1
                v.log.write(f"{v.name('motor_pwm')}: {len(pwm)} PWM values, need 4: dropped", "malformed")
                continue
            step = (stamp_ns(msg.header.stamp) - START_NS) // PHYSICS_STEP_NS
            now = first_step
            if config.pace == "realtime":
                wall = int((time.monotonic() - start) * NS_PER_S) // PHYSICS_STEP_NS
                now = min(max(wall, first_step), last_step)
            if step < v.last_step:
                v.out_of_order += 1
                v.log.write(f"command stamped step {step} after one for step {v.last_step}", "out of order")
                step = v.last_step
            if step < now:
                v.late += 1
                v.log.write(f"command for step {step} applied late, at step {now}", "late command")
                step = now
            v.last_step = step
            v.hold.schedule(step, (pwm[0], pwm[1], pwm[2], pwm[3]))

    def check_peers() -> None:
        now = time.monotonic()
        for v in fleet:
            if v.heard is not None and now - v.heard > config.peer_timeout_s:
                raise PeerSilent(
                    f"{v.namespace}: nothing from the chip for {now - v.heard:.1f} s "
                    f"(--peer-timeout {config.peer_timeout_s:g})"
                )

    def connected() -> bool:
        return all(
            v.digest is not None
            and all(s.get_num_connections() > 0 for s in v.subs)
            and all(v.pubs[key].get_num_connections() > 0 for key in SENSOR_TOPICS)
            for v in fleet
        )

    start = time.monotonic()
    cpu_start = time.process_time()
    ended, message = Ended.DONE, "flown"
    done = 0
    max_lag = 0.0
    try:
        publish_clock(0)
        deadline = time.monotonic() + config.connect_timeout_s
        while not connected():
            take(0.05, 0, 0, start)
            if time.monotonic() > deadline:
                missing = [v.namespace for v in fleet if v.digest is None]
                raise PeerSilent(
                    f"no chip node answered within --connect-timeout {config.connect_timeout_s:g} s"
                    + (f" (none in {', '.join(missing)})" if missing else " (subscriptions not connected)")
                )
        pause = time.monotonic() + start_delay_s
        while time.monotonic() < pause:
            take(min(0.05, max(0.0, pause - time.monotonic())), 0, 0, start)
        for v in fleet:
            v.heard = time.monotonic()
        if on_start is not None:
            on_start()
        start = time.monotonic()
        cpu_start = time.process_time()
        steps = clock.steps_per_sample
        for k in clock.samples():
            t_ns = clock.sample_ns(k)
            stamp = to_time(START_NS + t_ns)
            publish_clock(t_ns)
            wind = world.wind.velocity
            transforms = []
            for v, quad, craft in zip(fleet, quads, vehicles, strict=True):
                sample, truth = quad.sensors(), quad.truth()
                setpoint = setpoint_at(scenario.flight, craft.rest_height, sample.time)
                row = flight_row(sample, truth, UNKNOWN_ESTIMATE, setpoint, quad.pwm, wind)
                v.rows.append(row)
                _publish_sensors(v, classes, stamp, sample, truth)
                transforms.append(_transform(transform_class, stamp, v.frame, truth))
            tf_pub.publish(classes["tf"](transforms=transforms))
            first, last = clock.first_step(k), clock.first_step(k) + steps - 1
            end_ns = t_ns + period_ns
            while True:
                now = time.monotonic()
                if config.pace == "realtime":
                    remaining = start + end_ns / NS_PER_S - now
                    if remaining <= 0:
                        take(0.0, first, last, start)
                        max_lag = max(max_lag, -remaining)
                        break
                    take(min(remaining, config.heartbeat_s), first, last, start)
                else:
                    if all(
                        v.progress_ns >= end_ns
                        and v.received >= v.announced
                        and (not telemetry or v.telemetry_arrived >= v.telemetry_announced)
                        for v in fleet
                    ):
                        break
                    take(config.heartbeat_s, first, last, start)
                check_peers()
            for s, _ in clock.steps(k):
                for v, quad in zip(fleet, quads, strict=True):
                    quad.apply_pwm(v.hold.at(first + s))
                    if s == 0:
                        row = v.rows[-1]
                        row[PWM_COLUMNS] = quad.pwm
                        own = v.telemetry.fill(row, k)
                        v.told.append(own)
                        if on_row is not None:
                            on_row(v.index, row, own)
                if s == 0:
                    done = k + 1
                    if on_sample is not None:
                        on_sample(done, samples)
                world.step()
        publish_clock(clock.duration_ns)
    except KeyboardInterrupt:
        ended, message = Ended.INTERRUPTED, "interrupted"
    except PeerSilent as exc:
        ended, message = Ended.PEER_LOST, str(exc)
    except Mismatch as exc:
        ended, message = Ended.MISMATCH, str(exc)
    host_s = time.monotonic() - start
    cpu_s = time.process_time() - cpu_start
    node.close()
    outcomes = []
    for v in fleet:
        rows = np.array(v.rows[:done]) if done else np.empty((0, len(ROW_FIELDS)))
        link = {
            "to_chip": {"sent": done, "transport": "ros1", "namespace": v.namespace},
            "from_chip": {"motor_pwm": v.received, "status_commands": v.announced, "out_of_order": v.out_of_order,
                          "malformed": v.malformed},
        }  # fmt: skip
        commands = {"received": v.received, "late": v.late, "missed": max(0, done - v.received)}
        told = np.array(v.told[:done], dtype=float).reshape(len(v.told[:done]), len(v.telemetry.own))
        outcome = PhysicsOutcome(
            rows=rows, samples=samples, ended=ended, message=message, host_s=host_s, cpu_s=cpu_s, link=link,
            commands=commands, max_lag_s=max_lag, period_s=period_ns / NS_PER_S,
            telemetry={name: told[:, c].copy() for c, name in enumerate(v.telemetry.own)},
            telemetry_counts={"received": v.telemetry.received, "refused": v.telemetry_refused},
        )  # fmt: skip
        v.log.write(f"ended: {ended}: {message}")
        v.log.write(f"counts: {link}; commands {commands}")
        v.log.close()
        outcomes.append(outcome)
    return outcomes


def _publish_sensors(v: _Vehicle, classes: dict[str, Any], stamp: Any, sample: Any, truth: Any) -> None:
    imu = classes["imu"]()
    imu.header.stamp, imu.header.frame_id = stamp, v.frame
    imu.orientation.w = 1.0
    imu.orientation_covariance[0] = -1.0  # no orientation (sensor_msgs/Imu's convention)
    g, a = sample.gyro, sample.accel
    imu.angular_velocity.x, imu.angular_velocity.y, imu.angular_velocity.z = (float(x) for x in g)
    imu.linear_acceleration.x, imu.linear_acceleration.y, imu.linear_acceleration.z = (float(x) for x in a)
    v.pubs["imu"].publish(imu)
    mag = classes["magnetic"]()
    mag.header.stamp, mag.header.frame_id = stamp, v.frame
    mag.vector.x, mag.vector.y, mag.vector.z = (float(x) for x in sample.mag)
    v.pubs["magnetic"].publish(mag)
    height = classes["pressure_height"]()
    height.header.stamp, height.header.frame_id = stamp, v.frame
    height.point.z = float(sample.baro_altitude)
    v.pubs["pressure_height"].publish(height)
    alt = classes["altimeter"]()
    alt.header.stamp, alt.header.frame_id = stamp, v.frame
    alt.altitude, alt.pressure, alt.qnh = float(sample.baro_altitude), float(sample.baro_pressure), QNH_HPA
    v.pubs["altimeter"].publish(alt)
    odom = classes["ground_truth"]()
    odom.header.stamp, odom.header.frame_id = stamp, FRAME_WORLD
    odom.child_frame_id = v.frame
    p, q = odom.pose.pose.position, odom.pose.pose.orientation
    p.x, p.y, p.z = (float(x) for x in truth.position)
    q.w, q.x, q.y, q.z = (float(x) for x in truth.quaternion)
    lin, ang = odom.twist.twist.linear, odom.twist.twist.angular
    lin.x, lin.y, lin.z = (float(x) for x in truth.velocity)
    ang.x, ang.y, ang.z = (float(x) for x in truth.angular_velocity)
    v.pubs["ground_truth"].publish(odom)


def _transform(cls: Any, stamp: Any, frame: str, truth: Any) -> Any:
    t = cls()
    t.header.stamp, t.header.frame_id = stamp, FRAME_WORLD
    t.child_frame_id = frame
    tr, rot = t.transform.translation, t.transform.rotation
    tr.x, tr.y, tr.z = (float(x) for x in truth.position)
    rot.w, rot.x, rot.y, rot.z = (float(x) for x in truth.quaternion)
    return t
