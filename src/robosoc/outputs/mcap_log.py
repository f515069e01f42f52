"""A flight as an MCAP file with ROS 2 messages (``flight.mcap``), as rosbag2 writes one.

The topics, types and units are :data:`robosoc.outputs.ros2_flight.TOPICS`.  The file has the
``ros2`` profile; each schema is named ``pkg/msg/Type`` with the ``ros2msg`` text of the type and
of every type it uses; each channel has CDR messages and the ``offered_qos_profiles`` metadata
rosbag2 writes (:data:`OFFERED_QOS_PROFILES`).  The firmware's own telemetry adds a topic per value
(``/telemetry/<name>``, after each row's flight messages), which ``ros2 bag play`` and ``rosbags`` read.  Log
time, publish time and header stamp are the row's time after the start time (by default
:data:`robosoc.outputs.ros2_flight.START_NS`), so a flight gives the same bytes every time.  The
file is written under a temporary name and renamed (:func:`robosoc.output_files.atomic_open`), so
an interrupted write leaves no truncated ``flight.mcap``.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from mcap.well_known import MessageEncoding, Profile, SchemaEncoding
from mcap.writer import LIBRARY_IDENTIFIER
from mcap.writer import Writer as McapWriter

from robosoc import __version__, output_files
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.flight_log import read_flight_log
from robosoc.outputs.ros2_flight import (
    START_NS,
    cdr_encoder,
    message_definition,
    row_messages,
    stamp_ns,
    telemetry_messages,
    telemetry_topic,
)

LIBRARY = f"robosoc/{__version__} {LIBRARY_IDENTIFIER}"

# rosbag2's YAML of a publisher's offered QoS (the integer enums and "infinite" durations of
# Humble's rosbag2): history unknown (3), depth 0, reliable (1), volatile (2), automatic liveliness
# (1), as a reliable publisher such as tf2's broadcaster offers it and `ros2 bag record` stores it
_INFINITE = "    sec: 9223372036\n    nsec: 854775807\n"
OFFERED_QOS_PROFILES = (
    "- history: 3\n  depth: 0\n  reliability: 1\n  durability: 2\n"
    f"  deadline:\n{_INFINITE}  lifespan:\n{_INFINITE}"
    f"  liveliness: 1\n  liveliness_lease_duration:\n{_INFINITE}"
    "  avoid_ros_namespace_conventions: false"
)


def write_flight_mcap(
    rows: np.ndarray, path: Path, start_ns: int = START_NS, telemetry: Mapping[str, np.ndarray] | None = None
) -> int:
    """Write the flight ``rows`` (columns :data:`ROW_FIELDS`) to ``path``, their times counted from
    ``start_ns`` (ns since the Unix epoch); the number of messages.  ``telemetry``: the firmware's
    values under names of its own, one per row (NaN: none yet), a topic each.

    Raises:
        ValueError: ``rows`` does not have the columns of a flight; a telemetry value not one per row.
    """
    if rows.ndim != 2 or rows.shape[1] != len(ROW_FIELDS):
        raise ValueError(f"a flight has {len(ROW_FIELDS)} columns (robosoc.control.flight.ROW_FIELDS)")
    own = dict(telemetry or {})
    for name, values in own.items():
        if np.shape(values) != (len(rows),):
            raise ValueError(f"telemetry {name!r}: {np.shape(values)} values, expected one per row ({len(rows)})")
    topics = [telemetry_topic(name) for name in own]
    table = np.column_stack([np.asarray(v, dtype=float) for v in own.values()]) if own else None
    count = 0
    with output_files.atomic_open(path, "wb") as stream:
        writer = McapWriter(stream)
        writer.start(profile=Profile.ROS2, library=LIBRARY)
        schemas: dict[str, int] = {}
        channels: dict[str, int] = {}
        encoders = {}
        for k, row in enumerate(rows):
            messages = row_messages(row, start_ns)
            if table is not None:
                ns = stamp_ns(float(row[ROW_FIELDS.index("t")]), start_ns)
                messages = itertools.chain(messages, telemetry_messages(topics, table[k], ns))
            for topic, message, ns in messages:
                channel = channels.get(topic.name)
                if channel is None:
                    if topic.datatype not in schemas:
                        text = message_definition(topic.datatype).encode()
                        schemas[topic.datatype] = writer.register_schema(topic.datatype, SchemaEncoding.ROS2, text)
                        encoders[topic.datatype] = cdr_encoder(topic.datatype)
                    channel = writer.register_channel(
                        topic.name, MessageEncoding.CDR, schemas[topic.datatype],
                        {"offered_qos_profiles": OFFERED_QOS_PROFILES},
                    )  # fmt: skip
                    channels[topic.name] = channel
                data = encoders[topic.datatype](message)
                writer.add_message(channel, log_time=ns, data=data, publish_time=ns, sequence=count)
                count += 1
        writer.finish()
    return count


def flight_csv_to_mcap(csv_path: Path, mcap_path: Path, start_ns: int = START_NS) -> int:
    """Convert a flight log (``flight.csv``) to MCAP; the number of messages.

    Raises:
        ValueError: the CSV is not a robosoc flight log.
    """
    telemetry: dict[str, np.ndarray] = {}
    rows = read_flight_log(csv_path, [], telemetry=telemetry)
    return write_flight_mcap(rows, mcap_path, start_ns, telemetry)


__all__ = ["LIBRARY", "OFFERED_QOS_PROFILES", "flight_csv_to_mcap", "write_flight_mcap"]
