"""The chip and the physics as ROS 1 nodes (``serve chip --ros``, ``serve physics --ros``) through a
real ``roscore``: the flights they fly, what other ROS nodes see of them, and bad input.

Skipped where ROS 1 is not installed (``tests/ros_master.py``), except what needs no ROS: a
``--ros`` command on a machine without it fails clearly.  Flights are short and paced on simulated
time (``--pace fast``): the physics steps only once the chip has said how far it has simulated (and
every command and telemetry message it counts by then has come), so the flight must be the
lockstep flight row for row, the chip's estimate and telemetry columns too, however slow the host.
"""

from __future__ import annotations

import hashlib
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from robosoc.cli import app, exit_codes
from robosoc.config.scenario import FlightPlan, ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import ROW_FIELDS, fly
from robosoc.control.flight_log import read_flight_log
from robosoc.control.host import HostController
from robosoc.control.setpoint import setpoint_at
from robosoc.cosim import ros1
from robosoc.cosim.lockstep import ChipController, fly_chip, fly_lockstep_fleet
from robosoc.cosim.replay import replay
from robosoc.cosim.ros_topics import MSG_TEXT, TOPICS
from robosoc.outputs.flight_session import fleet_vehicles
from robosoc.physics.clock import START_NS
from ros_master import SYSTEM_PYTHON, Master, running_master, stop, stop_recorder, wait_all
from telemetry_project import counting_project

SCENARIO_TOML = "duration_s = {duration}\nvehicles = {vehicles}\n[flight]\ntakeoff_s = 0.3\nsteps = []\n"
PUBLISHER = Path(__file__).resolve().parents[1] / "ros_hector_publisher.py"


def scenario(duration: float = 1.0, vehicles: int = 1) -> ScenarioConfig:
    return ScenarioConfig(duration_s=duration, vehicles=vehicles, flight=FlightPlan(takeoff_s=0.3, steps=()))


@pytest.fixture(scope="module")
def master(tmp_path_factory: pytest.TempPathFactory):
    with running_master(tmp_path_factory.mktemp("ros")) as m:
        yield m


def scenario_file(folder: Path, duration: float = 1.0, vehicles: int = 1) -> Path:
    path = folder / "scenario.toml"
    path.write_text(SCENARIO_TOML.format(duration=duration, vehicles=vehicles))
    return path


def md5(text: str) -> str:
    return hashlib.md5(text.encode()).hexdigest()


# --- message types ------------------------------------------------------------------------------

HEADER_MD5 = md5("uint32 seq\ntime stamp\nstring frame_id")


def test_md5_sums_follow_the_ros_rule_and_rosbags() -> None:
    """hector's MotorPWM and Altimeter and robosoc's ChipStatus and Telemetry: the MD5 sum of the generated class
    is the one the ROS rule gives (comments out, a nested type replaced by its own sum) and the one
    rosbags (another implementation) computes from the same text."""
    if ros1_missing():
        pytest.skip(ros1_missing())
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    by_rule = {
        "hector_uav_msgs/MotorPWM": md5(f"{HEADER_MD5} header\nuint8[] pwm"),
        "hector_uav_msgs/Altimeter": md5(f"{HEADER_MD5} header\nfloat32 altitude\nfloat32 pressure\nfloat32 qnh"),
        "robosoc_msgs/ChipStatus": md5(f"{HEADER_MD5} header\nuint32 commands\nuint32 telemetry\nstring scenario"),
        "robosoc_msgs/Telemetry": md5(f"{HEADER_MD5} header\nuint32 sample\nstring[] names\nfloat64[] values"),
    }
    assert HEADER_MD5 == "2176decaecbce78abc3b96ef049fabed"  # std_msgs/Header, as every ROS 1 tool has it
    store = get_typestore(Stores.ROS1_NOETIC)
    ros2_name = {name: name.replace("/", "/msg/") for name in MSG_TEXT}  # rosbags names types so
    for name, text in MSG_TEXT.items():
        store.register(get_types_from_msg(text, ros2_name[name]))
    for name, expected in by_rule.items():
        cls = ros1.message_class(name)
        assert cls._md5sum == expected, name
        assert cls._type == name
        assert store.generate_msgdef(ros2_name[name], ros_version=1)[1] == expected, name
    # every type of the topic map exists, and the standard ones are the installed packages'
    for t in TOPICS:
        assert ros1.message_class(t.type)._type == t.type
    assert ros1.message_class("sensor_msgs/Imu")._md5sum == "6a62c6daae103f4ff57a132d6f95cec2"


def ros1_missing() -> str | None:
    from ros_master import ros_missing

    return ros_missing()


# --- bad input that needs no ROS ------------------------------------------------------------------


def test_ros_option_without_ros_installed(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """Without rospy, ``--ros`` says what to install (exit 2), and UDP options with it are refused."""
    monkeypatch.setitem(sys.modules, "rospy", None)  # import rospy raises ImportError
    monkeypatch.setattr(ros1, "DEBIAN_DIST_PACKAGES", tmp_path / "none")
    runner = CliRunner()
    result = runner.invoke(app, ["serve", "chip", "--ros", "--no-out", "--duration", "0.1"])
    assert result.exit_code == exit_codes.USAGE, result.output
    assert "rospy" in result.output and "apt-get install" in result.output
    result = runner.invoke(app, ["serve", "physics", "--ros", "--no-out", "--duration", "0.1"])
    assert result.exit_code == exit_codes.USAGE, result.output
    assert "rospy" in result.output
    result = runner.invoke(app, ["serve", "chip", "--ros", "--peer", "127.0.0.1:5000", "--no-out"])
    assert result.exit_code == exit_codes.USAGE and "--peer" in result.output
    result = runner.invoke(app, ["serve", "chip", "--ns", "/uav1", "--no-out"])
    assert result.exit_code == exit_codes.USAGE and "--ns" in result.output
    result = runner.invoke(app, ["serve", "chip", "--ros", "--ns", "/1bad", "--no-out"])
    assert result.exit_code == exit_codes.USAGE and "--ns" in result.output
    result = runner.invoke(app, ["serve", "physics", "--start-delay", "2", "--no-out"])
    assert result.exit_code == exit_codes.USAGE and "--start-delay" in result.output


# --- with a master --------------------------------------------------------------------------------


def test_no_master_is_a_clear_bounded_error(tmp_path: Path) -> None:
    if ros1_missing():
        pytest.skip(ros1_missing())
    from ros_master import SRC, free_port

    uri = f"http://127.0.0.1:{free_port()}"
    env = {"ROS_MASTER_URI": uri, "PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin", "HOME": str(tmp_path)}
    for side in ("chip", "physics"):
        start = time.monotonic()
        done = subprocess.run(
            [sys.executable, "-m", "robosoc", "serve", side, "--ros", "--no-out", "--duration", "0.1"],
            env=env, capture_output=True, text=True, timeout=60, check=False,
        )  # fmt: skip
        assert done.returncode == exit_codes.USAGE, done.stderr
        assert f"ROS_MASTER_URI={uri}" in done.stderr and "roscore" in done.stderr
        assert "Traceback" not in done.stderr
        assert time.monotonic() - start < 30


def test_two_nodes_fly_the_lockstep_flight(master: Master, tmp_path: Path) -> None:
    """physics + chip through roscore fly the lockstep flight row for row; rosbag records it: 100 Hz
    sensors, /clock from the start time on, PWM commands with hector's type and MD5 sum, the chip's
    estimate and telemetry equal to the lockstep chip's, a response time per job."""
    config = scenario(1.0)
    toml = scenario_file(tmp_path)
    bag = tmp_path / "flight.bag"
    recorder = master.start(["rosbag", "record", "-a", "-O", str(bag)], tmp_path / "rosbag.log")
    time.sleep(1.5)
    physics = master.robosoc(["serve", "physics", str(toml), "--ros", "--pace", "fast", "--start-delay", "5",
                              "--out", str(tmp_path / "p")], tmp_path / "physics.log")  # fmt: skip
    chip = master.robosoc(["serve", "chip", str(toml), "--ros", "--out", str(tmp_path / "c")], tmp_path / "chip.log")
    codes = wait_all([physics, chip], timeout=300)
    time.sleep(1.0)
    stop_recorder(recorder, bag)
    assert codes == [0, 0], (tmp_path / "physics.log").read_text() + (tmp_path / "chip.log").read_text()
    rows = read_flight_log(tmp_path / "p" / "flight.csv")
    lockstep = fly_chip(config, vehicle_preset(config.vehicle))
    assert rows.shape == lockstep.rows.shape
    np.testing.assert_array_equal(rows, lockstep.rows)  # the estimate too: the chip's telemetry, logged
    chip_json = json.loads((tmp_path / "c" / "chip.json").read_text())
    assert chip_json["complete"] and chip_json["readings"]["injected"] == 100
    assert chip_json["link"]["from_physics"]["imu"] == {
        "received": 100, "out_of_order": 0, "duplicate": 0, "off_rate": 0, "extra": 0, "outside": 0, "held": 0,
    }  # fmt: skip

    topics = read_bag_by_system_rosbag(master, bag, tmp_path)
    imu = topics["/raw_imu"]
    assert imu["type"] == "sensor_msgs/Imu" and len(imu["stamps"]) == 100
    assert np.all(np.diff(imu["stamps"]) == 10_000_000) and imu["stamps"][0] == START_NS
    clock = topics["/clock"]["values"]
    assert clock[0] == START_NS and clock[-1] == START_NS + 1_000_000_000
    assert np.all(np.diff(clock) == 10_000_000)
    pwm = topics["/motor_pwm"]
    assert pwm["type"] == "hector_uav_msgs/MotorPWM"
    assert pwm["md5sum"] == md5(f"{HEADER_MD5} header\nuint8[] pwm")
    assert [list(p) for p in pwm["values"]] == [list(c.pwm) for c in lockstep.run.commands]
    for t in ("/magnetic", "/pressure_height", "/altimeter", "/ground_truth/state", "/tf", "/chip/status"):
        assert t in topics, t
    # the estimate at sample k's stamp is what lockstep's row k + 1 holds (read after sample k)
    est = topics["/chip/estimate"]
    assert len(est["values"]) >= 98
    for stamp, (w, x, y, z, h) in zip(est["stamps"], est["values"], strict=True):
        k = (stamp - START_NS) // 10_000_000
        if k + 1 < len(lockstep.rows):
            row = lockstep.rows[k + 1]
            assert (w, x, y, z, h) == tuple(row[ROW_FIELDS.index(n)] for n in ("est_qw", "est_qx", "est_qy", "est_qz",
                                                                                 "est_height"))  # fmt: skip
    telemetry = topics["/chip/telemetry"]
    assert telemetry["type"] == "robosoc_msgs/Telemetry" and len(telemetry["values"]) >= 98
    for stamp, (sample, names, values) in zip(telemetry["stamps"], telemetry["values"], strict=True):
        assert names == ["est_qw", "est_qx", "est_qy", "est_qz", "est_height", "est_vz"]  # the project's
        assert stamp == START_NS + sample * 10_000_000
        if sample + 1 < len(lockstep.rows):
            assert values[:5] == [lockstep.rows[sample + 1, ROW_FIELDS.index(n)] for n in names[:5]]
    assert not any(t.startswith("/telemetry/") for t in topics)  # no value under a name of its own
    jobs = lockstep.run.jobs_of("estimator")
    responses = topics["/chip/response_time/estimator"]["values"]
    expected = [(j.completion_cycle - j.release_cycle) * lockstep.run.clock_ns / 1000 for j in jobs]
    assert len(responses) >= 98 and responses == pytest.approx(expected[: len(responses)], rel=1e-12)


def test_the_project_telemetry_is_published_logged_and_recorded(master: Master, tmp_path: Path) -> None:
    """A project with a value under a name of its own (a counter of its jobs): the chip node
    publishes it on /telemetry/jobs_counted (std_msgs/Float64, the MCAP file's topic name) and every
    name on /chip/telemetry; the physics node logs it in flight.csv, whose every row and column
    equals the lockstep flight's; rosbag records both topics."""
    project = counting_project(tmp_path)
    toml = tmp_path / "scenario.toml"
    toml.write_text(SCENARIO_TOML.format(duration=0.3, vehicles=1) + f'[firmware]\nproject = "{project}"\n')
    lockstep = tmp_path / "lockstep"
    result = CliRunner().invoke(app, ["fly", "--scenario", str(toml), "--out", str(lockstep)])
    assert result.exit_code == 0, result.output
    bag = tmp_path / "flight.bag"
    # an earlier physics node set use_sim_time: a recorder started with it would wait for /clock
    assert master.run(["rosparam", "set", "/use_sim_time", "false"]).returncode == 0
    recorder = master.start(["rosbag", "record", "-a", "-O", str(bag)], tmp_path / "rosbag.log")
    time.sleep(1.5)
    physics = master.robosoc(["serve", "physics", str(toml), "--ros", "--pace", "fast", "--start-delay", "4",
                              "--out", str(tmp_path / "p")], tmp_path / "physics.log")  # fmt: skip
    chip = master.robosoc(["serve", "chip", str(toml), "--ros", "--out", str(tmp_path / "c")], tmp_path / "chip.log")
    codes = wait_all([physics, chip], timeout=300)
    time.sleep(1.0)
    stop_recorder(recorder, bag)
    assert codes == [0, 0], (tmp_path / "physics.log").read_text() + (tmp_path / "chip.log").read_text()
    told: dict[str, np.ndarray] = {}
    rows = read_flight_log(tmp_path / "p" / "flight.csv", telemetry=told)
    expected_told: dict[str, np.ndarray] = {}
    np.testing.assert_array_equal(rows, read_flight_log(lockstep / "flight.csv", telemetry=expected_told))
    np.testing.assert_array_equal(told["jobs_counted"], [math.nan, *range(1, 30)])
    np.testing.assert_array_equal(told["jobs_counted"], expected_told["jobs_counted"])
    physics_json = json.loads((tmp_path / "p" / "physics.json").read_text())
    assert physics_json["telemetry"] == {"received": 29, "refused": 0}
    topics = read_bag_by_system_rosbag(master, bag, tmp_path)
    value = topics["/telemetry/jobs_counted"]
    assert value["type"] == "std_msgs/Float64" and value["values"] == list(range(1, 30))
    entries = topics["/chip/telemetry"]
    assert [(stamp, v) for stamp, v in zip(entries["stamps"], entries["values"], strict=True)] == [
        (START_NS + k * 10_000_000, [k, ["jobs_counted"], [k + 1.0]]) for k in range(29)
    ]
    assert "/chip/estimate" not in topics  # the project publishes no estimate


BAG_READER = """
import json, sys, rosbag
out = {}
for topic, msg, t, conn in [(a, b, c, None) for a, b, c in []]:
    pass
bag = rosbag.Bag(sys.argv[1])
info = bag.get_type_and_topic_info().topics
conns = {c.topic: c for c in bag._get_connections()}
for topic, msg, t in bag.read_messages():
    d = out.setdefault(topic, {"type": info[topic].msg_type, "md5sum": conns[topic].md5sum, "stamps": [], "values": []})
    if hasattr(msg, "header"):
        d["stamps"].append(msg.header.stamp.to_nsec())
    if topic == "/clock":
        d["values"].append(msg.clock.to_nsec())
    elif topic.endswith("motor_pwm"):
        d["values"].append(list(bytearray(msg.pwm)))
    elif topic.endswith("chip/estimate"):
        o = msg.pose.orientation
        d["values"].append([o.w, o.x, o.y, o.z, msg.pose.position.z])
    elif topic.endswith("chip/telemetry"):
        d["values"].append([msg.sample, list(msg.names), list(msg.values)])
    elif "response_time" in topic or "/telemetry/" in topic:
        d["values"].append(msg.data)
json.dump(out, open(sys.argv[2], "w"))
"""


def read_bag_by_system_rosbag(master: Master, bag: Path, folder: Path) -> dict:
    """The bag read by ROS 1's own ``rosbag`` (system Python): per topic its type, MD5, stamps, values."""
    script = folder / "read_bag.py"
    script.write_text(BAG_READER)
    done = master.run([SYSTEM_PYTHON, str(script), str(bag), str(folder / "bag.json")])
    assert done.returncode == 0, done.stderr
    info = master.run(["rosbag", "info", str(bag)])
    assert info.returncode == 0 and "hector_uav_msgs/MotorPWM" in info.stdout
    return json.loads((folder / "bag.json").read_text())


def recorded_readings(config: ScenarioConfig, t0_ns: int, path: Path) -> np.ndarray:
    """A host-controller flight's sensor readings as a hector-style recording (stamps from ``t0_ns``);
    the rows with their times and setpoints as the chip node will see them."""
    vehicle = vehicle_preset(config.vehicle)
    rows = fly(config, vehicle, HostController.for_scenario(config, vehicle))
    col = {n: i for i, n in enumerate(ROW_FIELDS)}
    names = ["gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z", "mag_x", "mag_y", "mag_z", "baro_altitude"]
    lines = ["stamp_ns," + ",".join(names)]
    for r in rows:
        stamp = t0_ns + round(r[col["t"]] * 1e9)
        lines.append(f"{stamp}," + ",".join(repr(float(r[col[n]])) for n in names))
        t = (stamp - t0_ns) / 1e9
        sp = setpoint_at(config.flight, vehicle.rest_height, t)
        r[col["t"]] = t
        for n, v in (("sp_roll", sp.roll), ("sp_pitch", sp.pitch), ("sp_yaw", sp.yaw), ("sp_height", sp.height),
                     ("sp_height_rate", sp.height_rate), ("sp_height_accel", sp.height_accel),
                     ("armed", float(sp.armed))):  # fmt: skip
            r[col[n]] = v
    path.write_text("\n".join(lines) + "\n")
    return rows


def test_a_foreign_node_gets_100_hz_pwm(master: Master, tmp_path: Path) -> None:
    """A rospy node robosoc did not write publishes recorded hector-style sensor messages (stamped
    from 1000 s on) in /quad7; the chip answers each with a MotorPWM of hector's type and MD5 sum,
    100 Hz in the stamps, equal to what the replay harness computes from the same readings."""
    config = scenario(1.0)
    t0 = 1000 * 10**9
    rows = recorded_readings(config, t0, tmp_path / "readings.csv")
    chip = master.robosoc(["serve", "chip", str(scenario_file(tmp_path)), "--ros", "--ns", "/quad7",
                           "--out", str(tmp_path / "c")], tmp_path / "chip.log")  # fmt: skip
    node = master.start([str(PUBLISHER), str(tmp_path / "readings.csv"), str(tmp_path / "got.json"), "--ns", "/quad7"],
                        tmp_path / "publisher.log", python=SYSTEM_PYTHON)  # fmt: skip
    codes = wait_all([chip, node], timeout=300)
    assert codes == [0, 0], (tmp_path / "chip.log").read_text() + (tmp_path / "publisher.log").read_text()
    got = json.loads((tmp_path / "got.json").read_text())["commands"]
    expected = replay(rows, config.firmware, vehicle=vehicle_preset(config.vehicle), scenario=config)
    assert len(got) == len(expected.commands) == 100
    assert {c["type"] for c in got} == {"hector_uav_msgs/MotorPWM"}
    assert {c["md5sum"] for c in got} == {md5(f"{HEADER_MD5} header\nuint8[] pwm")}
    assert [c["pwm"] for c in got] == [list(c.pwm) for c in expected.commands]
    first = expected.samples[0].cycle
    stamps = [c["stamp_ns"] - t0 for c in got]
    assert stamps == [math.floor((c.cycle - first) * expected.clock_ns) for c in expected.commands]
    periods = np.diff(stamps)
    assert np.median(periods) == pytest.approx(10e6, abs=50e3)  # 100 Hz in the stamps


def test_bad_sensor_messages_are_counted(master: Master, tmp_path: Path) -> None:
    """A duplicated raw_imu message, one out of order and a missing one (a double interval) are
    counted in chip.json; the rest of the flight is answered."""
    config = scenario(1.0)
    t0 = 50 * 10**9
    recorded_readings(config, t0, tmp_path / "readings.csv")
    chip = master.robosoc(["serve", "chip", str(scenario_file(tmp_path)), "--ros", "--ns", "/faulty",
                           "--out", str(tmp_path / "c")], tmp_path / "chip.log")  # fmt: skip
    node = master.start([str(PUBLISHER), str(tmp_path / "readings.csv"), str(tmp_path / "got.json"), "--ns",
                         "/faulty", "--faults"], tmp_path / "publisher.log", python=SYSTEM_PYTHON)  # fmt: skip
    codes = wait_all([chip, node], timeout=300)
    assert codes == [0, 0], (tmp_path / "chip.log").read_text() + (tmp_path / "publisher.log").read_text()
    imu = json.loads((tmp_path / "c" / "chip.json").read_text())["link"]["from_physics"]["imu"]
    assert imu == {"received": 101, "out_of_order": 1, "duplicate": 1, "off_rate": 1, "extra": 0, "outside": 0,
                   "held": 0}  # fmt: skip
    assert len(json.loads((tmp_path / "got.json").read_text())["commands"]) == 99


def test_wrong_type_and_missing_namespace_are_refused(master: Master, tmp_path: Path) -> None:
    """A sensor topic of another type, and a namespace no vehicle is in, end the chip node at once
    with exit 2 and a message naming the topic, the types, the namespaces there are."""
    wrong = master.start(["rostopic", "pub", "/wrong/raw_imu", "std_msgs/String", "data: x", "-r", "5"],
                         tmp_path / "wrong.log")  # fmt: skip
    other = master.start(["rostopic", "pub", "/uav1/raw_imu", "sensor_msgs/Imu", "{}", "-r", "5"],
                         tmp_path / "other.log")  # fmt: skip
    try:
        time.sleep(3)
        done = master.run([sys.executable, "-m", "robosoc", "serve", "chip", "--ros", "--ns", "/wrong", "--no-out",
                           "--connect-timeout", "20"], timeout=60)  # fmt: skip
        assert done.returncode == exit_codes.USAGE, done.stderr
        assert "/wrong/raw_imu is published as std_msgs/String, expected sensor_msgs/Imu" in done.stderr
        start = time.monotonic()
        done = master.run([sys.executable, "-m", "robosoc", "serve", "chip", "--ros", "--ns", "/uav3", "--no-out",
                           "--connect-timeout", "60"], timeout=60)  # fmt: skip
        assert done.returncode == exit_codes.USAGE, done.stderr
        assert "--ns /uav3: no vehicle there" in done.stderr and "/uav1" in done.stderr
        assert time.monotonic() - start < 30  # the grace, not the connect timeout
    finally:
        stop(wrong)
        stop(other)


def test_two_vehicles_in_namespaces(master: Master, tmp_path: Path) -> None:
    """--vehicles 2: the physics publishes /uav1/... and /uav2/..., a chip node serves each, and each
    vehicle's flight is the lockstep fleet's row for row."""
    config = scenario(0.6, vehicles=2)
    toml = scenario_file(tmp_path, 0.6, 2)
    physics = master.robosoc(["serve", "physics", str(toml), "--ros", "--pace", "fast", "--out", str(tmp_path / "p")],
                             tmp_path / "physics.log")  # fmt: skip
    chips = [master.robosoc(chip_args(toml, f"/uav{i}", tmp_path / f"c{i}"), tmp_path / f"chip{i}.log") for i in (1, 2)]
    codes = wait_all([physics, *chips], timeout=300)
    logs = "".join((tmp_path / n).read_text() for n in ("physics.log", "chip1.log", "chip2.log"))
    assert codes == [0, 0, 0], logs
    vehicles = fleet_vehicles(config)
    canonical = vehicle_preset(config.vehicle)
    expected = fly_lockstep_fleet(config, vehicles, [ChipController(config, canonical) for _ in vehicles])
    for i in (1, 2):
        rows = read_flight_log(tmp_path / "p" / f"vehicle-{i}" / "flight.csv")
        np.testing.assert_array_equal(rows, expected[i - 1])
        physics_json = json.loads((tmp_path / "p" / f"vehicle-{i}" / "physics.json").read_text())
        assert physics_json["namespace"] == f"/uav{i}" and physics_json["commands"]["received"] == 60
    assert not np.array_equal(expected[0][:, 1:4], expected[1][:, 1:4])  # two vehicles, not one twice


def chip_args(toml: Path, ns: str, out: Path) -> list[str]:
    return ["serve", "chip", str(toml), "--ros", "--ns", ns, "--out", str(out)]


def test_realtime_pacing_and_sim_time(master: Master, tmp_path: Path) -> None:
    """--pace realtime keeps to the wall clock (a 2 s flight takes at least 2 s); use_sim_time is set,
    and ``rostopic hz`` started after it (so on /clock's time) shows the sensors' 100 Hz."""
    toml = scenario_file(tmp_path, 2.0)
    physics = master.robosoc(["serve", "physics", str(toml), "--ros", "--pace", "realtime", "--start-delay", "2",
                              "--out", str(tmp_path / "p")], tmp_path / "physics.log")  # fmt: skip
    deadline = time.monotonic() + 60
    while master.run(["rosparam", "get", "/use_sim_time"]).stdout.strip() != "true":
        assert time.monotonic() < deadline, "use_sim_time was not set"
        time.sleep(0.2)
    hz = master.start(["rostopic", "hz", "/raw_imu"], tmp_path / "hz.log")
    chip = master.robosoc(["serve", "chip", str(toml), "--ros", "--out", str(tmp_path / "c")], tmp_path / "chip.log")
    codes = wait_all([physics, chip], timeout=300)
    stop(hz)
    assert codes == [0, 0], (tmp_path / "physics.log").read_text() + (tmp_path / "chip.log").read_text()
    record = json.loads((tmp_path / "p" / "physics.json").read_text())
    assert record["host_s"] >= 2.0 and record["commands"]["received"] == 200
    rates = [float(line.split(":")[1]) for line in (tmp_path / "hz.log").read_text().splitlines()
             if line.strip().startswith("average rate:")]  # fmt: skip
    assert rates and all(r == pytest.approx(100.0, abs=1.0) for r in rates), (tmp_path / "hz.log").read_text()
