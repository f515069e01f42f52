"""The ROS interface as data: which topics the chip node and the physics node use, of which types.

The topic map is transport-free (no ROS import here): :mod:`robosoc.cosim.ros1` puts it on ROS 1
(rospy); a ROS 2 transport would read the same :data:`TOPICS` and name the types the ROS 2 way
(``sensor_msgs/msg/Imu``).  Names follow a Gazebo + hector_quadrotor world (hector_quadrotor's
``quadrotor_sensors.gazebo.xacro`` and the plugins' defaults), relative to a vehicle's namespace
(``/uav1/raw_imu``) unless absolute (``/clock``, ``/tf``).

Types of hector's own package (``hector_uav_msgs``) and robosoc's (``robosoc_msgs``) are given as
their ``.msg`` text (:data:`MSG_TEXT`): the ROS 1 transport generates the message classes from it,
so the MD5 sums are hector's (a node built against hector_uav_msgs talks to robosoc's).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "CHIP",
    "FRAME_BODY",
    "FRAME_WORLD",
    "MSG_TEXT",
    "PHYSICS",
    "SENSOR_TOPICS",
    "TOPICS",
    "Topic",
    "topic",
    "vehicle_namespace",
]

PHYSICS = "physics"
CHIP = "chip"
FRAME_WORLD = "world"
FRAME_BODY = "base_link"


@dataclass(frozen=True)
class Topic:
    """One topic: its name (relative to the vehicle's namespace unless it starts with ``/``), its
    type (``package/Type``), which node publishes it, and what it carries."""

    key: str
    name: str
    type: str
    publisher: str
    doc: str

    @property
    def per_vehicle(self) -> bool:
        return not self.name.startswith("/")


TOPICS: tuple[Topic, ...] = (
    Topic("imu", "raw_imu", "sensor_msgs/Imu", PHYSICS,
          "gyro (angular_velocity, rad/s) and specific force (linear_acceleration, m/s^2), body FLU; "
          "orientation unknown (orientation_covariance[0] = -1); one message per sensor sample"),
    Topic("magnetic", "magnetic", "geometry_msgs/Vector3Stamped", PHYSICS,
          "magnetic field, body FLU, in units of the field's magnitude (hector's magnitude 1.0)"),
    Topic("pressure_height", "pressure_height", "geometry_msgs/PointStamped", PHYSICS,
          "barometric height (point.z, m)"),
    Topic("altimeter", "altimeter", "hector_uav_msgs/Altimeter", PHYSICS,
          "barometric altitude (m), pressure (hPa) and QNH (hPa)"),
    Topic("ground_truth", "ground_truth/state", "nav_msgs/Odometry", PHYSICS,
          "true pose (world frame) and twist (linear: world frame, angular: body frame)"),
    Topic("tf", "/tf", "tf2_msgs/TFMessage", PHYSICS, "world -> NS/base_link of every vehicle, true pose"),
    Topic("clock", "/clock", "rosgraph_msgs/Clock", PHYSICS,
          "simulated time, once per sensor sample (use_sim_time)"),
    Topic("motor_pwm", "motor_pwm", "hector_uav_msgs/MotorPWM", CHIP,
          "the firmware's PWM command (0..255 per motor), stamped when it reached the I/O tile"),
    Topic("status", "chip/status", "robosoc_msgs/ChipStatus", CHIP,
          "the chip's progress: simulated up to header.stamp, commands and telemetry messages published by then"),
    Topic("telemetry", "chip/telemetry", "robosoc_msgs/Telemetry", CHIP,
          "the firmware's telemetry (its project's [[telemetry]], every name) after each read at a sample "
          "period's close, stamped with the sensor sample it includes: what the physics node logs"),
    Topic("telemetry_value", "telemetry/{name}", "std_msgs/Float64", CHIP,
          "each telemetry value under a name of its own (not the estimate's), at each read: one topic "
          "per value, named as in flight.mcap (rqt_plot NS/telemetry/NAME/data)"),
    Topic("estimate", "chip/estimate", "geometry_msgs/PoseStamped", CHIP,
          "the estimator task's attitude (orientation) and height (position.z; x and y NaN), "
          "stamped with the sensor sample it includes"),
    Topic("response_time", "chip/response_time/{task}", "std_msgs/Float64", CHIP,
          "each job's response time (release to completion, microseconds), one topic per task"),
)  # fmt: skip

SENSOR_TOPICS = ("imu", "magnetic", "pressure_height")
"""What the chip node subscribes to: one firmware sensor sample per ``imu`` message, with the
newest ``magnetic`` and ``pressure_height`` readings stamped at or before it."""

MSG_TEXT: dict[str, str] = {
    # hector_quadrotor (noetic-devel), hector_uav_msgs/msg/*.msg, verbatim
    "hector_uav_msgs/MotorPWM": "Header header\nuint8[] pwm\n",
    "hector_uav_msgs/Altimeter": "Header header\nfloat32 altitude\nfloat32 pressure\nfloat32 qnh\n",
    # robosoc's own
    "robosoc_msgs/ChipStatus": (
        "# The chip node's progress: it has simulated up to header.stamp (the flight's time, as the\n"
        "# sensor stamps), and had published `commands` motor_pwm messages by then.\n"
        "Header header\n"
        "uint32 commands\n"
        "# chip/telemetry messages published by then\n"
        "uint32 telemetry\n"
        "# digest of the scenario and vehicle the firmware was built for (hex)\n"
        "string scenario\n"
    ),
    "robosoc_msgs/Telemetry": (
        "# The firmware's telemetry after the host's read at the close of a sensor sample's period\n"
        "# (docs/firmware-projects.md): header.stamp is that sample's time.\n"
        "Header header\n"
        "# the sensor sample's number\n"
        "uint32 sample\n"
        "# the project's [[telemetry]] names, in its order, and the newest value of each (NaN before its first read)\n"
        "string[] names\n"
        "float64[] values\n"
    ),
}


def topic(key: str) -> Topic:
    """The topic of ``key``.

    Raises:
        KeyError: no such topic.
    """
    for t in TOPICS:
        if t.key == key:
            return t
    raise KeyError(key)


def vehicle_namespace(index: int, vehicles: int) -> str:
    """The namespace of vehicle ``index`` (0-based) of ``vehicles``: ``/`` for a single vehicle
    (hector's ``spawn_quadrotor.launch``), ``/uav1``, ``/uav2`` ... for several
    (``spawn_two_quadrotors.launch``)."""
    return "/" if vehicles == 1 else f"/uav{index + 1}"
