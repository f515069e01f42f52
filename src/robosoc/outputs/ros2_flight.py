"""A flight row as ROS 2 messages: the topics, their message definitions and how columns fill them.

Shared by the MCAP log (:mod:`robosoc.outputs.mcap_log`) and the live Foxglove server
(:mod:`robosoc.outputs.foxglove_live`), so a recorded flight and a live one look the same.

Every column of :data:`robosoc.control.flight.ROW_FIELDS` lands in exactly one message field
(:data:`TOPICS`), with the ROS unit where it differs (pressure hPa → Pa); ``/tf`` repeats the poses
as transforms.  Types are named as ROS 2 names them (``sensor_msgs/msg/Imu``).  Frames: ``world``
(the physics world, z up) for poses and wind, ``base_link`` (body, FLU) for the sensors.  The
magnetometer is the simulator's unit field (``sensor_msgs/MagneticField`` asks for tesla; the
model has no field strength, so the values are the unit vector as the firmware sees it).  The
estimate has a height but no horizontal position: its pose's x and y are NaN.  Rows whose estimate
is unknown (NaN, as for the chip controller without an estimate probe) publish no estimate.

The firmware's telemetry under names of its own (:mod:`robosoc.host.telemetry`) is one topic per
value, ``/telemetry/<name>`` (``std_msgs/msg/Float64``), published from the first row that has a
value (:func:`telemetry_messages`).

Stamps are the row's simulated time after a start time (:data:`START_NS`, 2026-01-01T00:00:00Z by
default): a fixed date, so that the same flight gives the same bytes, and one that viewers show as
a date rather than as 1970.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robosoc.control.flight import ROW_FIELDS
from robosoc.outputs.ros2_cdr import CdrEncoder
from robosoc.physics.clock import START_NS as START_NS
from robosoc.physics.clock import START_TIME as START_TIME

FRAME_WORLD = "world"
FRAME_BODY = "base_link"
FRAME_ESTIMATE = "base_link_estimate"
HPA_TO_PA = 100.0

# message definitions as ROS 2 ships them (rosidl .msg text, types named ``pkg/Type`` as the .msg
# files and the ``MSG:`` sections of a schema name them), and robosoc's own two
_DEFINITIONS: dict[str, str] = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
    "rosgraph_msgs/Clock": "builtin_interfaces/Time clock\n",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "std_msgs/Float64": "float64 data\n",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/Pose": "Point position\nQuaternion orientation\n",
    "geometry_msgs/PoseStamped": "std_msgs/Header header\nPose pose\n",
    "geometry_msgs/Vector3Stamped": "std_msgs/Header header\nVector3 vector\n",
    "geometry_msgs/Transform": "Vector3 translation\nQuaternion rotation\n",
    "geometry_msgs/TransformStamped": "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
    "tf2_msgs/TFMessage": "geometry_msgs/TransformStamped[] transforms\n",
    "sensor_msgs/Imu": (
        "std_msgs/Header header\n"
        "geometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
        "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
        "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n"
    ),
    "sensor_msgs/MagneticField": (
        "std_msgs/Header header\ngeometry_msgs/Vector3 magnetic_field\nfloat64[9] magnetic_field_covariance\n"
    ),
    "sensor_msgs/FluidPressure": "std_msgs/Header header\nfloat64 fluid_pressure\nfloat64 variance\n",
    "robosoc_msgs/Setpoint": (
        "# the flight plan's setpoint at the sample time (angles in rad, height in m above ground)\n"
        "std_msgs/Header header\n"
        "float64 roll\nfloat64 pitch\nfloat64 yaw\nfloat64 height\n"
        "float64 height_rate\nfloat64 height_accel\n"
        "bool armed\n"
    ),
    "robosoc_msgs/Pwm": (
        "# motor commands in force from the sample time on (PWM counts 0..255, motors 0..3)\n"
        "std_msgs/Header header\nuint8[4] pwm\n"
    ),
}

_SEPARATOR = "=" * 80


def _package(datatype: str) -> str:
    return datatype.split("/")[0]


def short_name(datatype: str) -> str:
    """``pkg/Type`` for ``pkg/msg/Type`` (the name fields and ``MSG:`` sections use)."""
    parts = datatype.split("/")
    return f"{parts[0]}/{parts[-1]}"


def _field_types(datatype: str) -> list[str]:
    """Full names of the message types ``datatype``'s fields use (a bare name is in its package)."""
    out = []
    for line in _DEFINITIONS[datatype].splitlines():
        line = line.split("#")[0].strip()
        if not line:
            continue
        kind = line.split()[0].split("[")[0]
        if kind[0].isupper() or "/" in kind:
            out.append(kind if "/" in kind else f"{_package(datatype)}/{kind}")
    return out


def message_definition(datatype: str) -> str:
    """The ``ros2msg`` schema text of ``datatype`` (``pkg/msg/Type`` or ``pkg/Type``): its
    definition, then each type it uses once (``MSG: pkg/Type`` sections), as rosbag2 writes it."""
    datatype = short_name(datatype)
    seen: list[str] = []
    stack = _field_types(datatype)
    while stack:
        kind = stack.pop(0)
        if kind not in seen:
            seen.append(kind)
            stack.extend(_field_types(kind))
    parts = [_DEFINITIONS[datatype]]
    parts.extend(f"{_SEPARATOR}\nMSG: {kind}\n{_DEFINITIONS[kind]}" for kind in seen)
    return "".join(parts)


_CDR = CdrEncoder(_DEFINITIONS)


def cdr_encoder(datatype: str) -> Callable[[Mapping[str, object]], bytes]:
    """The function encoding a message (a dict, as :func:`row_messages` gives it) of ``datatype``
    (``pkg/msg/Type``) to CDR bytes."""
    return _CDR.encoder(short_name(datatype))


@dataclass(frozen=True)
class Transform:
    """A child frame of ``world`` on ``/tf``: the columns of its translation (x, y, z) and of its
    rotation (a quaternion w, x, y, z).  A row where any of them is NaN does not publish it."""

    child: str
    translation: tuple[str, str, str]
    rotation: tuple[str, str, str, str]


@dataclass(frozen=True)
class Topic:
    """One topic of a flight: its ROS 2 type (``pkg/msg/Type``), frame, fixed fields, and the
    columns it carries.

    ``columns`` maps a dotted field path to (column of :data:`ROW_FIELDS`, factor); ``fixed`` maps
    a path to a constant.  ``optional`` topics are left out for a row whose columns are all NaN.
    A ``tf2_msgs/msg/TFMessage`` topic carries ``transforms`` instead (left out for a row that has
    none of them).
    """

    name: str
    datatype: str
    frame: str | None
    columns: dict[str, tuple[str, float]]
    fixed: dict[str, object] = field(default_factory=dict)
    optional: bool = False
    transforms: tuple[Transform, ...] = ()


_UNKNOWN_COVARIANCE = [0.0] * 9
_NO_ORIENTATION = [-1.0] + [0.0] * 8  # REP 145 / sensor_msgs/Imu: element 0 = -1: no orientation


def _xyz(prefix: str, columns: tuple[str, str, str], factor: float = 1.0) -> dict[str, tuple[str, float]]:
    return {f"{prefix}.{axis}": (col, factor) for axis, col in zip("xyz", columns, strict=True)}


def _quaternion(prefix: str, q: str) -> dict[str, tuple[str, float]]:
    return {f"{prefix}.{axis}": (f"{q}{axis}", 1.0) for axis in "wxyz"}


TF_TRANSFORMS: tuple[Transform, ...] = (
    Transform(FRAME_BODY, ("x", "y", "z"), ("qw", "qx", "qy", "qz")),
    # the estimator has no horizontal position: the estimate's frame is drawn at the true x, y
    Transform(FRAME_ESTIMATE, ("x", "y", "est_height"), ("est_qw", "est_qx", "est_qy", "est_qz")),
)
"""``/tf``: ``world`` → ``base_link`` (the true pose) and ``world`` → ``base_link_estimate`` (the
estimated height and attitude, at the true x and y) where the estimate is known."""

TOPICS: tuple[Topic, ...] = (
    Topic(
        "/imu", "sensor_msgs/msg/Imu", FRAME_BODY,
        {**_xyz("angular_velocity", ("gyro_x", "gyro_y", "gyro_z")),
         **_xyz("linear_acceleration", ("accel_x", "accel_y", "accel_z"))},
        {"orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}, "orientation_covariance": _NO_ORIENTATION,
         "angular_velocity_covariance": _UNKNOWN_COVARIANCE, "linear_acceleration_covariance": _UNKNOWN_COVARIANCE},
    ),
    Topic(
        "/mag", "sensor_msgs/msg/MagneticField", FRAME_BODY, _xyz("magnetic_field", ("mag_x", "mag_y", "mag_z")),
        {"magnetic_field_covariance": _UNKNOWN_COVARIANCE},
    ),
    Topic(
        "/baro/pressure", "sensor_msgs/msg/FluidPressure", FRAME_BODY,
        {"fluid_pressure": ("baro_pressure", HPA_TO_PA)}, {"variance": 0.0},
    ),
    Topic("/baro/altitude", "std_msgs/msg/Float64", None, {"data": ("baro_altitude", 1.0)}),
    Topic(
        "/truth/pose", "geometry_msgs/msg/PoseStamped", FRAME_WORLD,
        {**_xyz("pose.position", ("x", "y", "z")), **_quaternion("pose.orientation", "q")},
    ),
    Topic("/truth/euler", "geometry_msgs/msg/Vector3Stamped", FRAME_WORLD, _xyz("vector", ("roll", "pitch", "yaw"))),
    Topic(
        "/estimate/pose", "geometry_msgs/msg/PoseStamped", FRAME_WORLD,
        {"pose.position.z": ("est_height", 1.0), **_quaternion("pose.orientation", "est_q")},
        {"pose": {"position": {"x": math.nan, "y": math.nan}}}, optional=True,
    ),
    Topic(
        "/estimate/euler", "geometry_msgs/msg/Vector3Stamped", FRAME_WORLD,
        _xyz("vector", ("est_roll", "est_pitch", "est_yaw")), optional=True,
    ),
    Topic(
        "/setpoint", "robosoc_msgs/msg/Setpoint", None,
        {name: (f"sp_{name}", 1.0) for name in ("roll", "pitch", "yaw", "height", "height_rate", "height_accel")}
        | {"armed": ("armed", 1.0)},
    ),
    Topic("/pwm", "robosoc_msgs/msg/Pwm", None, {f"pwm.{i}": (f"pwm{i}", 1.0) for i in range(4)}, {"pwm": [0] * 4}),
    Topic("/wind", "geometry_msgs/msg/Vector3Stamped", FRAME_WORLD, _xyz("vector", ("wind_x", "wind_y", "wind_z"))),
    Topic("/tf", "tf2_msgs/msg/TFMessage", None, {}, transforms=TF_TRANSFORMS),
)  # fmt: skip
"""The topics of a flight; every column but ``t`` (the stamp) is in exactly one of them besides
``/tf``."""

_INDEX = {name: i for i, name in enumerate(ROW_FIELDS)}


def _set(message: dict, path: str, value: object) -> None:
    *parents, leaf = path.split(".")
    node: Any = message  # nested messages: dicts, and lists of numbers
    for key in parents:
        node = node[key]
    if isinstance(node, list):
        node[int(leaf)] = value
    else:
        node[leaf] = value


def _template(topic: Topic) -> dict:
    """The message with every column field present (zero) and the fixed fields, before filling."""
    message: dict = {}
    if "header" in _DEFINITIONS[short_name(topic.datatype)]:
        message["header"] = {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": topic.frame or ""}
    for key, value in topic.fixed.items():
        _merge(message, key, value)
    for path in topic.columns:
        *parents, leaf = path.split(".")
        node = message
        for key in parents:
            node = node.setdefault(key, {})
        if isinstance(node, dict):
            node.setdefault(leaf, 0.0)
    return message


def _merge(node: dict, key: str, value: object) -> None:
    if isinstance(value, list):
        node[key] = list(value)
    elif isinstance(value, dict):
        for k, v in value.items():
            _merge(node.setdefault(key, {}), k, v)
    else:
        node[key] = value


def _convert(datatype: str, path: str, value: float) -> object:
    if datatype == "robosoc_msgs/msg/Pwm":
        return int(value)
    if path == "armed":
        return value > 0.5
    return value


def stamp_ns(t: float, start_ns: int = START_NS) -> int:
    """A row time [s] as integer nanoseconds after ``start_ns`` (the messages' log time and stamp)."""
    return start_ns + round(t * 1e9)


def _stamp(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def _transforms(topic: Topic, row: np.ndarray, ns: int) -> list[dict]:
    out = []
    for tf in topic.transforms:
        translation = [float(row[_INDEX[c]]) for c in tf.translation]
        rotation = [float(row[_INDEX[c]]) for c in tf.rotation]
        if not all(math.isfinite(v) for v in translation + rotation):
            continue
        out.append({
            "header": {"stamp": _stamp(ns), "frame_id": FRAME_WORLD},
            "child_frame_id": tf.child,
            "transform": {"translation": dict(zip("xyz", translation, strict=True)),
                          "rotation": dict(zip("wxyz", rotation, strict=True))},
        })  # fmt: skip
    return out


TELEMETRY_PREFIX = "/telemetry/"
"""Topic of a telemetry value named ``name``: ``/telemetry/<name>``."""


def telemetry_topic(name: str) -> Topic:
    """The topic of the firmware's telemetry value ``name`` (a C identifier: a valid ROS 2 name)."""
    return Topic(f"{TELEMETRY_PREFIX}{name}", "std_msgs/msg/Float64", None, {"data": (name, 1.0)})


def telemetry_messages(topics: Sequence[Topic], values: Sequence[float], ns: int) -> Iterator[tuple[Topic, dict, int]]:
    """(topic, message, stamp in ns) of one row's telemetry ``values`` (one per ``topics``, NaN:
    none read yet, no message)."""
    for topic, value in zip(topics, values, strict=True):
        if not math.isnan(value):
            yield topic, {"data": float(value)}, ns


def row_messages(row: np.ndarray, start_ns: int = START_NS) -> Iterator[tuple[Topic, dict, int]]:
    """(topic, message as a dict for the CDR encoder, stamp in ns) of one flight row whose time
    counts from ``start_ns`` (ns since the Unix epoch)."""
    ns = stamp_ns(float(row[_INDEX["t"]]), start_ns)
    for topic in TOPICS:
        if topic.transforms:
            transforms = _transforms(topic, row, ns)
            if transforms:
                yield topic, {"transforms": transforms}, ns
            continue
        values = {path: float(row[_INDEX[col]]) * factor for path, (col, factor) in topic.columns.items()}
        if topic.optional and all(math.isnan(v) for v in values.values()):
            continue
        message = _template(topic)
        if "header" in message:
            message["header"]["stamp"] = _stamp(ns)
        for path, value in values.items():
            _set(message, path, _convert(topic.datatype, path, value))
        yield topic, message, ns


__all__ = [
    "FRAME_BODY", "FRAME_ESTIMATE", "FRAME_WORLD", "START_NS", "START_TIME", "TELEMETRY_PREFIX", "TF_TRANSFORMS",
    "TOPICS", "Topic", "Transform", "cdr_encoder", "message_definition", "row_messages", "short_name", "stamp_ns",
    "telemetry_messages", "telemetry_topic",
]  # fmt: skip
