"""The flight MCAP read back with third-party readers: the ``mcap`` reader with the ROS 2 decoder
of ``mcap-ros2-support``, and ``rosbags`` (AnyReader, its CDR serializer and ``rosbags-convert``)."""

from __future__ import annotations

import dataclasses
import math
import re
from datetime import datetime
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import ROW_FIELDS, fly
from robosoc.control.flight_log import CsvFlightLog
from robosoc.control.host import HostController
from robosoc.outputs.mcap_log import flight_csv_to_mcap, write_flight_mcap
from robosoc.outputs.ros2_flight import START_NS, START_TIME
from ros_bags import convert, read_bag

SECONDS = 0.5


@pytest.fixture(scope="module")
def rows() -> np.ndarray:
    scenario = ScenarioConfig(duration_s=SECONDS)
    vehicle = vehicle_preset(scenario.vehicle)
    scenario = dataclasses.replace(scenario, seed=4)
    return fly(scenario, vehicle, HostController.for_scenario(scenario, vehicle))


def _decoded(path: Path) -> dict[str, list]:
    out: dict[str, list] = {}
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            assert schema.encoding == "ros2msg" and channel.message_encoding == "cdr"
            out.setdefault(channel.topic, []).append((schema.name, message.log_time, decoded))
    return out


def _expected(row: dict[str, float]) -> dict[str, dict[str, float]]:
    """Per topic, field path → value, written out by hand from the ROS message definitions."""
    return {
        "/imu": {"angular_velocity.x": row["gyro_x"], "angular_velocity.y": row["gyro_y"],
                 "angular_velocity.z": row["gyro_z"], "linear_acceleration.x": row["accel_x"],
                 "linear_acceleration.y": row["accel_y"], "linear_acceleration.z": row["accel_z"],
                 "orientation_covariance.0": -1.0},
        "/mag": {"magnetic_field.x": row["mag_x"], "magnetic_field.y": row["mag_y"], "magnetic_field.z": row["mag_z"]},
        "/baro/pressure": {"fluid_pressure": row["baro_pressure"] * 100.0},
        "/baro/altitude": {"data": row["baro_altitude"]},
        "/truth/pose": {"pose.position.x": row["x"], "pose.position.y": row["y"], "pose.position.z": row["z"],
                        "pose.orientation.w": row["qw"], "pose.orientation.x": row["qx"],
                        "pose.orientation.y": row["qy"], "pose.orientation.z": row["qz"]},
        "/truth/euler": {"vector.x": row["roll"], "vector.y": row["pitch"], "vector.z": row["yaw"]},
        "/estimate/pose": {"pose.position.z": row["est_height"], "pose.orientation.w": row["est_qw"],
                           "pose.orientation.x": row["est_qx"], "pose.orientation.y": row["est_qy"],
                           "pose.orientation.z": row["est_qz"]},
        "/estimate/euler": {"vector.x": row["est_roll"], "vector.y": row["est_pitch"], "vector.z": row["est_yaw"]},
        "/setpoint": {"roll": row["sp_roll"], "pitch": row["sp_pitch"], "yaw": row["sp_yaw"],
                      "height": row["sp_height"], "height_rate": row["sp_height_rate"],
                      "height_accel": row["sp_height_accel"], "armed": row["armed"] > 0.5},
        "/pwm": {f"pwm.{i}": row[f"pwm{i}"] for i in range(4)},
        "/wind": {"vector.x": row["wind_x"], "vector.y": row["wind_y"], "vector.z": row["wind_z"]},
        "/tf": {"transforms.0.header.frame_id": "world", "transforms.0.child_frame_id": "base_link",
                "transforms.0.transform.translation.x": row["x"], "transforms.0.transform.translation.y": row["y"],
                "transforms.0.transform.translation.z": row["z"], "transforms.0.transform.rotation.w": row["qw"],
                "transforms.0.transform.rotation.x": row["qx"], "transforms.0.transform.rotation.y": row["qy"],
                "transforms.0.transform.rotation.z": row["qz"],
                "transforms.1.header.frame_id": "world", "transforms.1.child_frame_id": "base_link_estimate",
                "transforms.1.transform.translation.x": row["x"], "transforms.1.transform.translation.y": row["y"],
                "transforms.1.transform.translation.z": row["est_height"],
                "transforms.1.transform.rotation.w": row["est_qw"], "transforms.1.transform.rotation.x": row["est_qx"],
                "transforms.1.transform.rotation.y": row["est_qy"], "transforms.1.transform.rotation.z": row["est_qz"]},
    }  # fmt: skip


def _get(message: object, path: str) -> object:
    node = message
    for key in path.split("."):
        node = node[int(key)] if key.isdigit() else getattr(node, key)
    return node


def test_every_message_decodes_and_equals_its_row(rows: np.ndarray, tmp_path: Path) -> None:
    path = tmp_path / "flight.mcap"
    count = write_flight_mcap(rows, path)
    decoded = _decoded(path)
    expected_topics = set(_expected(dict.fromkeys(ROW_FIELDS, 0.0)))
    assert set(decoded) == expected_topics
    assert count == sum(len(v) for v in decoded.values()) == len(rows) * len(expected_topics)
    for topic, messages in decoded.items():
        assert len(messages) == len(rows), topic
        for k, (_, log_time, message) in enumerate(messages):
            row = dict(zip(ROW_FIELDS, (float(v) for v in rows[k]), strict=True))
            ns = 1_767_225_600 * 10**9 + round(row["t"] * 1e9)  # 2026-01-01T00:00:00Z + t
            assert log_time == ns
            headers = [m.header for m in getattr(message, "transforms", [])] or [getattr(message, "header", None)]
            for header in filter(None, headers):
                assert header.stamp.sec * 10**9 + header.stamp.nanosec == ns
            for field, value in _expected(row)[topic].items():
                got = _get(message, field)
                assert got == value, (topic, k, field, got, value)


def test_types_and_schema_text_are_the_ros2_ones(rows: np.ndarray, tmp_path: Path) -> None:
    path = tmp_path / "flight.mcap"
    write_flight_mcap(rows[:2], path)
    with path.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert reader.get_header().profile == "ros2"
    schemas = {s.name: s.data.decode() for s in summary.schemas.values()}
    topics = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
    assert topics["/imu"] == "sensor_msgs/msg/Imu"
    assert topics["/mag"] == "sensor_msgs/msg/MagneticField"
    assert topics["/baro/pressure"] == "sensor_msgs/msg/FluidPressure"
    assert topics["/truth/pose"] == topics["/estimate/pose"] == "geometry_msgs/msg/PoseStamped"
    assert topics["/tf"] == "tf2_msgs/msg/TFMessage"
    # a ros2msg schema carries every type it uses, once (named pkg/Type, as the fields name them)
    imu = schemas["sensor_msgs/msg/Imu"]
    for dep in ("std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/Quaternion", "geometry_msgs/Vector3"):
        assert imu.count(f"MSG: {dep}\n") == 1, dep
    assert schemas["tf2_msgs/msg/TFMessage"].startswith("geometry_msgs/TransformStamped[] transforms\n")
    assert "uint8[4] pwm" in schemas["robosoc_msgs/msg/Pwm"]


def test_unknown_estimate_publishes_no_estimate_and_csv_converts(rows: np.ndarray, tmp_path: Path) -> None:
    chip_like = rows[:5].copy()
    for name in ROW_FIELDS:
        if name.startswith("est_"):
            chip_like[:, ROW_FIELDS.index(name)] = math.nan
    csv = tmp_path / "flight.csv"
    with CsvFlightLog(csv) as log:
        for row in chip_like:
            log.write(row)
    out = tmp_path / "flight.mcap"
    flight_csv_to_mcap(csv, out)
    decoded = _decoded(out)
    assert "/estimate/pose" not in decoded and "/estimate/euler" not in decoded
    assert [_get(m, "pose.position.z") for _, _, m in decoded["/truth/pose"]] == list(
        chip_like[:, ROW_FIELDS.index("z")]
    )
    # /tf has the true pose only
    assert [[t.child_frame_id for t in m.transforms] for _, _, m in decoded["/tf"]] == [["base_link"]] * 5
    assert not list(tmp_path.glob("*.partial"))


def test_rows_without_flight_columns_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="columns"):
        write_flight_mcap(np.zeros((3, 4)), tmp_path / "x.mcap")
    assert not (tmp_path / "x.mcap").exists()


def test_one_schema_per_type_and_messages_numbered_in_write_order(rows: np.ndarray, tmp_path: Path) -> None:
    path = tmp_path / "flight.mcap"
    count = write_flight_mcap(rows[:3], path)
    with path.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        messages = list(reader.iter_messages(log_time_order=False))
    names = [s.name for s in summary.schemas.values()]
    assert len(names) == len(set(names))  # each type registered once, shared by its topics
    assert len(summary.channels) == len({c.topic for c in summary.channels.values()})
    assert [m.sequence for _, _, m in messages] == list(range(count))
    assert all(m.publish_time == m.log_time for _, _, m in messages)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["flight.mcap"]  # no partial file left


ROS1_MD5 = {  # the md5 sums ROS 1 gives these types (rosbag, rostopic check them)
    "sensor_msgs/msg/Imu": "6a62c6daae103f4ff57a132d6f95cec2",
    "geometry_msgs/msg/PoseStamped": "d3812c3cbc69362b77dc0b19b345f8f5",
    "tf2_msgs/msg/TFMessage": "94810edda583a504dfda3829e70d7eec",
}


def _equals_rows(messages: dict[str, list], rows: np.ndarray) -> None:
    """Every topic's messages, one per row, with the values and stamps of that row."""
    assert set(messages) == set(_expected(dict.fromkeys(ROW_FIELDS, 0.0)))
    for topic, got in messages.items():
        assert len(got) == len(rows), topic
        for k, m in enumerate(got):
            row = dict(zip(ROW_FIELDS, (float(v) for v in rows[k]), strict=True))
            assert m.timestamp == 1_767_225_600 * 10**9 + round(row["t"] * 1e9), (topic, k)
            for path, value in _expected(row)[topic].items():
                assert _get(m.message, path) == value, (topic, k, path)


def test_rosbags_decodes_every_message_of_every_topic_and_encodes_the_same_bytes(
    rows: np.ndarray, tmp_path: Path
) -> None:
    path = tmp_path / "flight.mcap"
    write_flight_mcap(rows, path)
    messages, reader = read_bag(path)
    _equals_rows(messages, rows)
    # the types come from the file (no ROS installation): named as ROS 2 names them
    assert {c.topic: c.msgtype for c in reader.connections}["/imu"] == "sensor_msgs/msg/Imu"
    for connection in reader.connections:
        # offered_qos_profiles on every channel, as rosbag2 stores it: one reliable, volatile publisher
        (qos,) = connection.ext.offered_qos_profiles
        assert (qos.reliability.name, qos.durability.name, qos.liveliness.name) == (
            "RELIABLE", "VOLATILE", "AUTOMATIC"), connection.topic  # fmt: skip
        assert connection.ext.serialization_format == "cdr"
    # robosoc's CDR encoder and rosbags' serializer give the same bytes for every message
    for topic, got in messages.items():
        for m in got:
            assert reader.typestore.serialize_cdr(m.message, m.msgtype).tobytes() == m.raw, topic


def test_rosbags_convert_makes_a_ros1_bag_of_the_same_messages(rows: np.ndarray, tmp_path: Path) -> None:
    path = tmp_path / "flight.mcap"
    write_flight_mcap(rows, path)
    result = convert(path, tmp_path / "flight.bag")
    assert result.returncode == 0, result.stderr
    messages, reader = read_bag(tmp_path / "flight.bag")
    assert reader.is2 is False  # a ROS 1 bag
    _equals_rows(messages, rows)
    digests = {c.msgtype: c.digest for c in reader.connections}
    assert {k: digests[k] for k in ROS1_MD5} == ROS1_MD5


def test_the_start_time_sets_every_stamp_and_the_same_flight_gives_the_same_bytes(
    rows: np.ndarray, tmp_path: Path
) -> None:
    first, second, at_zero = tmp_path / "a.mcap", tmp_path / "b.mcap", tmp_path / "c.mcap"
    write_flight_mcap(rows[:20], first)
    write_flight_mcap(rows[:20], second)
    assert first.read_bytes() == second.read_bytes()
    assert START_NS == 1_767_225_600 * 10**9
    assert datetime.fromisoformat(START_TIME).timestamp() * 10**9 == START_NS
    write_flight_mcap(rows[:20], at_zero, start_ns=0)
    shifted, _ = read_bag(at_zero)
    t = [round(v * 1e9) for v in rows[:20, ROW_FIELDS.index("t")]]
    assert [m.timestamp for m in shifted["/imu"]] == t
    assert [m.message.header.stamp.sec * 10**9 + m.message.header.stamp.nanosec for m in shifted["/imu"]] == t


def test_robosoc_imports_no_private_module_of_mcap_ros2() -> None:
    root = Path(__file__).resolve().parents[2]
    private = re.compile(r"mcap_ros2\.\s*_|from\s+mcap_ros2\s+import\s+\(?\s*_")
    files = [*root.joinpath("src").rglob("*.py"), *root.joinpath("tests").rglob("*.py")]
    assert len(files) > 50
    assert [str(f) for f in files if private.search(f.read_text())] == []
