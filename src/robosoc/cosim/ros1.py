"""ROS 1 as a transport: rospy loaded on demand, the master checked, message classes, a node.

robosoc installs and runs without ROS: nothing here is imported until a ``--ros`` command asks for
it (:func:`load`).  ROS 1 comes from the system (Debian/Ubuntu: ``apt-get install ros-core
python3-rospy python3-rosbag python3-sensor-msgs python3-geometry-msgs python3-nav-msgs
python3-tf2-msgs``), whose Python packages live in ``/usr/lib/python3/dist-packages``; a Python of
the same minor version that does not see them (a virtual environment, pyenv) is pointed there.

* :func:`check_master`: the master at ``ROS_MASTER_URI`` answers within a bounded time, or
  :class:`RosUnavailable` names the address (rospy itself would wait for it forever);
* :func:`message_class`: the class of a type -- the installed package's (``sensor_msgs/Imu``), or
  generated from its ``.msg`` text (:data:`robosoc.cosim.ros_topics.MSG_TEXT`) with genpy, so
  hector's types have hector's MD5 sums;
* :class:`Node`: the process's node (rospy allows one), its publishers and subscribers, the
  master's view of who publishes what, and every message that arrives in one queue for the node's
  loop (rospy calls back on its own threads).
"""

from __future__ import annotations

import importlib
import os
import queue
import socket
import sys
import time
import xmlrpc.client
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any
from urllib.parse import urlparse

from robosoc.cosim.ros_topics import MSG_TEXT

__all__ = [
    "DEBIAN_DIST_PACKAGES",
    "DEFAULT_MASTER_URI",
    "Arrival",
    "Node",
    "RosUnavailable",
    "check_master",
    "full_name",
    "load",
    "message_class",
    "stamp_ns",
    "to_time",
]

DEBIAN_DIST_PACKAGES = Path("/usr/lib/python3/dist-packages")
DEFAULT_MASTER_URI = "http://localhost:11311"
MASTER_TIMEOUT_S = 3.0
"""How long the master gets to answer (:func:`check_master`)."""

INSTALL_HINT = (
    "install ROS 1 (Debian/Ubuntu: apt-get install ros-core python3-rospy python3-rosbag python3-sensor-msgs "
    "python3-geometry-msgs python3-nav-msgs python3-tf2-msgs python3-rosgraph-msgs)"
)


class RosUnavailable(Exception):
    """ROS cannot be used: not installed, no master, a topic of another type (the message says which)."""


def load() -> ModuleType:
    """rospy, imported (from Debian's dist-packages if the running Python does not see it).

    Raises:
        RosUnavailable: rospy cannot be imported.
    """
    try:
        return importlib.import_module("rospy")
    except ImportError:
        pass
    debian = str(DEBIAN_DIST_PACKAGES)
    if (DEBIAN_DIST_PACKAGES / "rospy").is_dir() and debian not in sys.path:
        sys.path.append(debian)  # after the running Python's own packages: those win
        try:
            return importlib.import_module("rospy")
        except ImportError as exc:
            raise RosUnavailable(f"--ros: rospy in {debian} does not import ({exc}); {INSTALL_HINT}") from None
    raise RosUnavailable(f"--ros: ROS 1's Python client (rospy) is not installed; {INSTALL_HINT}")


def check_master(timeout_s: float = MASTER_TIMEOUT_S) -> str:
    """The master's URI, once it has answered (within ``timeout_s``); ``ROS_MASTER_URI`` set to
    the default when it was not set.

    Raises:
        RosUnavailable: it did not answer (the message names ROS_MASTER_URI and its value).
    """
    uri = os.environ.get("ROS_MASTER_URI", "").strip()
    named = f"ROS_MASTER_URI={uri}"
    if not uri:
        uri = DEFAULT_MASTER_URI
        named = f"ROS_MASTER_URI (not set; tried the default {uri})"
        os.environ["ROS_MASTER_URI"] = uri
    parsed = urlparse(uri)
    if parsed.scheme != "http" or not parsed.hostname:
        raise RosUnavailable(f"{named}: not an address such as {DEFAULT_MASTER_URI}")
    try:
        port = parsed.port or 11311
    except ValueError:
        raise RosUnavailable(f"{named}: not an address such as {DEFAULT_MASTER_URI}") from None
    try:
        with socket.create_connection((parsed.hostname, port), timeout=timeout_s):
            pass
        code, _, _ = _timed_proxy(uri, timeout_s).getPid("/robosoc")
    except (OSError, xmlrpc.client.Error, ValueError) as exc:
        raise RosUnavailable(
            f"no ROS master answers at {named} ({exc}); start one with `roscore`, or set ROS_MASTER_URI to its address"
        ) from None
    if code != 1:
        raise RosUnavailable(f"the ROS master at {named} refused a request (code {code})")
    return uri


class _TimeoutTransport(xmlrpc.client.Transport):
    def __init__(self, timeout_s: float) -> None:
        super().__init__()
        self.timeout_s = timeout_s

    def make_connection(self, host: Any) -> Any:
        connection = super().make_connection(host)
        connection.timeout = self.timeout_s
        return connection


def _timed_proxy(uri: str, timeout_s: float) -> Any:
    return xmlrpc.client.ServerProxy(uri, transport=_TimeoutTransport(timeout_s))


_GENERATED: dict[str, Any] = {}


def message_class(type_name: str) -> Any:
    """The message class of ``type_name`` (``package/Type``): the installed package's, or one
    generated from :data:`MSG_TEXT` (hector's and robosoc's types).

    Raises:
        RosUnavailable: the type's package is not installed.
    """
    package, _, name = type_name.partition("/")
    if type_name in MSG_TEXT:
        if type_name not in _GENERATED:
            load()
            dynamic = importlib.import_module("genpy.dynamic")
            header = importlib.import_module("std_msgs.msg").Header
            text = MSG_TEXT[type_name] + "\n" + "=" * 80 + "\nMSG: std_msgs/Header\n" + header._full_text
            _GENERATED.update(dynamic.generate_dynamic(type_name, text))
        return _GENERATED[type_name]
    load()
    try:
        return getattr(importlib.import_module(f"{package}.msg"), name)
    except (ImportError, AttributeError):
        debian = package.replace("_", "-")
        raise RosUnavailable(
            f"--ros: the ROS message type {type_name} is not installed (Debian: apt-get install python3-{debian})"
        ) from None


def stamp_ns(stamp: Any) -> int:
    """A ROS time as integer nanoseconds."""
    return int(stamp.secs) * 1_000_000_000 + int(stamp.nsecs)


def to_time(ns: int) -> Any:
    """Integer nanoseconds as a ROS time."""
    rospy = load()
    return rospy.Time(ns // 1_000_000_000, ns % 1_000_000_000)


def full_name(namespace: str, name: str) -> str:
    """``name`` in ``namespace`` (``/uav1`` + ``raw_imu`` -> ``/uav1/raw_imu``; absolute names stay)."""
    if name.startswith("/"):
        return name
    return namespace.rstrip("/") + "/" + name


@dataclass(frozen=True)
class Arrival:
    """A message as the node's loop takes it: which subscription (its key), the message, when it came."""

    key: Any
    message: Any
    at: float


class Node:
    """The process's ROS node (``rospy.init_node`` once; Ctrl-C stays Python's KeyboardInterrupt).

    Raises:
        RosUnavailable: ROS is not installed or no master answers.
    """

    def __init__(self, name: str) -> None:
        self.rospy = load()
        self.uri = check_master()
        if not self.rospy.core.is_initialized():
            self.rospy.init_node(name, anonymous=True, disable_signals=True, disable_rosout=False)
        self.inbox: queue.SimpleQueue[Arrival] = queue.SimpleQueue()
        self.publishers: list[Any] = []
        self.subscribers: list[Any] = []

    def publisher(self, name: str, type_name: str, *, latch: bool = False, queue_size: int = 1000) -> Any:
        pub = self.rospy.Publisher(name, message_class(type_name), latch=latch, queue_size=queue_size, tcp_nodelay=True)
        self.publishers.append(pub)
        return pub

    def subscribe(self, name: str, type_name: str, key: Any) -> Any:
        """Subscribe to ``name``: each message goes to :attr:`inbox` as an :class:`Arrival` with ``key``."""
        put = self.inbox.put

        def arrived(message: Any) -> None:
            put(Arrival(key, message, time.monotonic()))

        sub = self.rospy.Subscriber(name, message_class(type_name), arrived, queue_size=None, tcp_nodelay=True)
        self.subscribers.append(sub)
        return sub

    def take(self, timeout: float) -> list[Arrival]:
        """Wait up to ``timeout`` s for a message; every message that is there."""
        out: list[Arrival] = []
        try:
            out.append(self.inbox.get(timeout=max(0.0, timeout)) if timeout > 0 else self.inbox.get_nowait())
        except queue.Empty:
            return out
        while True:
            try:
                out.append(self.inbox.get_nowait())
            except queue.Empty:
                return out

    def published_types(self) -> dict[str, str]:
        """Topic -> type of every topic some node publishes, as the master says."""
        master = importlib.import_module("rosgraph").Master(self.rospy.get_name())
        return dict(master.getPublishedTopics("/"))

    def set_param(self, name: str, value: object) -> None:
        self.rospy.set_param(name, value)

    def close(self) -> None:
        for item in (*self.subscribers, *self.publishers):
            item.unregister()
        self.subscribers.clear()
        self.publishers.clear()
